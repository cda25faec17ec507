#pragma once
// OpenCV's predefined ArUco dictionaries by the names scenario files and flight configurations
// use ("DICT_4X4_50", ...): one table for the flight software, the renderer and the scenario
// loader. Header-only; users must have OpenCV's aruco headers (all three link opencv_aruco).

#include <optional>
#include <string_view>

#include <opencv2/aruco/dictionary.hpp>

namespace shelfcross {

struct ArucoDictionaryEntry {
  const char* name;
  int id;    ///< cv::aruco::PREDEFINED_DICTIONARY_NAME
  int size;  ///< number of markers
};

inline constexpr ArucoDictionaryEntry kArucoDictionaries[] = {
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50, 50},         {"DICT_4X4_100", cv::aruco::DICT_4X4_100, 100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250, 250},      {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000, 1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50, 50},         {"DICT_5X5_100", cv::aruco::DICT_5X5_100, 100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250, 250},      {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000, 1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50, 50},         {"DICT_6X6_100", cv::aruco::DICT_6X6_100, 100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250, 250},      {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000, 1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50, 50},         {"DICT_7X7_100", cv::aruco::DICT_7X7_100, 100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250, 250},      {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000, 1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL, 1024},
    {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5, 30},
    {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9, 35},
    {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10, 2320},
    {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11, 587},
};

/// The entry of OpenCV's dictionary name ("DICT_4X4_50", case-sensitive), or nullptr for a name
/// not in the table.
inline const ArucoDictionaryEntry* find_aruco_dictionary(std::string_view name) {
  for (const ArucoDictionaryEntry& e : kArucoDictionaries) {
    if (name == e.name) return &e;
  }
  return nullptr;
}

}  // namespace shelfcross
