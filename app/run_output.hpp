#pragma once
// Writing one run's outputs (shared by `shelfcross run` and `shelfcross replay`):
//   DIR/run.json         outcome, detail, metrics, hash, seed, drawn dispersions, inventory
//   DIR/trajectory.csv   truth and phase at cosim.trajectory_rate_hz
//   DIR/events.log       phases, commands, replies, contacts, outcome, stamped
//   DIR/video.mp4        (with --video) the camera as the flight software received it, with
//                        its detections drawn on it: H.264 (`avc1`) in MP4, yuv420p, at the
//                        camera's rate and size (30 fps, 960 x 720 for the Tello), which
//                        browsers play.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "verification/cosim.hpp"

namespace shelfcross::app {

/// Runs `setup` with a renderer of its own and writes the outputs; returns the result.
verification::RunResult run_and_write(const verification::RunSetup& setup, const std::filesystem::path& dir,
                                      bool video);

/// The replay video: H.264 in MP4 through OpenCV's FFmpeg backend (libx264). Pictures are
/// placed by their source index, so the video keeps the camera's timeline: a picture that never
/// arrived is filled with the last one written, marked as not received.
class ReplayVideo {
 public:
  /// Throws std::runtime_error when the file cannot be opened for H.264 writing.
  ReplayVideo(const std::filesystem::path& path, double fps, cv::Size size);
  /// One received picture (already annotated), with its source index.
  void write(const cv::Mat& annotated, std::int64_t frame);
  std::int64_t frames_written() const { return written_; }

 private:
  cv::VideoWriter writer_;
  cv::Size size_;
  std::optional<std::int64_t> last_frame_;
  cv::Mat last_;
  std::int64_t written_ = 0;
};

}  // namespace shelfcross::app
