#pragma once
// Test helper: draws shelves as the Tello's camera would see them, with plain OpenCV (the
// flight software's tests may not use render/). Tags are filled squares in the tag colour at
// the projected post/beam intersections, boxes are brown front faces carrying an ArUco marker
// (cv::aruco::drawMarker on a white sheet, warped onto the projected face), posts and beams
// are dark blue bars, the background a grey wall. Points go through cv::projectPoints, with
// the lens distortion when asked. Painter's order: farthest shelf first.

#include <algorithm>
#include <array>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/camera.hpp"

namespace shelfcross::flight_sw::testing {

struct DrawnBox {
  int level = 1;
  int column = 1;
  int id = 0;
};

struct DrawnShelf {
  KnownShelf geometry;            ///< pitches, thicknesses, tag and marker sizes
  double base_height_m = 0.30;    ///< lowest beam centre line above the floor
  Eigen::Vector3d origin_W_m = Eigen::Vector3d(3.0, 0.0, 0.0);  ///< shelf frame S (warehouse.hpp)
  double yaw_rad = 0.0;
  std::vector<DrawnBox> boxes;
  double box_size_m = 0.24;
};

struct Scene {
  std::vector<DrawnShelf> shelves;
  cv::Scalar tag_bgr{60, 200, 40};
  cv::Scalar bar_bgr{140, 64, 38};
  cv::Scalar box_bgr{77, 117, 158};
  cv::Scalar wall_bgr{185, 185, 180};
  double brightness = 1.0;  ///< every colour scaled (lighting changes)
};

/// The paper's test shelf (4 x 4, columns 34/48/34/48 cm, rows 34 cm).
inline DrawnShelf paper_shelf(Eigen::Vector3d origin_W_m = Eigen::Vector3d(3.0, 0.0, 0.0)) {
  DrawnShelf s;
  s.origin_W_m = origin_W_m;
  return s;
}

/// X_WC of the camera for a body pose (ZYX yaw, pitch, roll) and a mount.
inline Eigen::Isometry3d camera_pose_W(const Eigen::Vector3d& p_WB_m, double yaw_rad,
                                       double pitch_rad = 0.0, double roll_rad = 0.0,
                                       const CameraMount& mount = {}) {
  const Eigen::Matrix3d R_WB = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = R_WB * rotation_body_from_camera(mount.pitch_rad);
  X_WC.translation() = p_WB_m + R_WB * mount.p_BC_B_m;
  return X_WC;
}

/// A point of shelf frame S in the world.
inline Eigen::Vector3d shelf_to_world(const DrawnShelf& s, const Eigen::Vector3d& p_S) {
  return s.origin_W_m + Eigen::AngleAxisd(s.yaw_rad, Eigen::Vector3d::UnitZ()) * p_S;
}

/// y_S of post i and z_S of beam j (shelfcross/warehouse.hpp conventions).
inline double post_y(const DrawnShelf& s, int i) {
  double w = 0.0;
  for (double p : s.geometry.column_pitch_m) w += p;
  double y = 0.5 * w;
  for (int k = 0; k < i; ++k) y -= s.geometry.column_pitch_m[static_cast<size_t>(k)];
  return y;
}
inline double beam_z(const DrawnShelf& s, int j) {
  double z = s.base_height_m;
  for (int k = 0; k < j; ++k) z += s.geometry.row_pitch_m[static_cast<size_t>(k)];
  return z;
}

class Drawer {
 public:
  Drawer(const CameraIntrinsics& k, bool distort) : k_(k) {
    K_ = cv::Matx33d(k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1);
    if (distort) dist_ = cv::Vec<double, 5>(k.k1, k.k2, k.p1, k.p2, k.k3);
  }

  cv::Mat draw(const Scene& scene, const Eigen::Isometry3d& X_WC) const {
    const double b = scene.brightness;
    cv::Mat img(k_.height_px, k_.width_px, CV_8UC3, scene.wall_bgr * b);
    const Eigen::Isometry3d X_CW = X_WC.inverse();
    std::vector<const DrawnShelf*> order;
    for (const auto& s : scene.shelves) order.push_back(&s);
    std::sort(order.begin(), order.end(), [&](const DrawnShelf* a, const DrawnShelf* c) {
      return (a->origin_W_m - X_WC.translation()).norm() > (c->origin_W_m - X_WC.translation()).norm();
    });
    for (const DrawnShelf* s : order) draw_shelf(img, scene, *s, X_CW);
    return img;
  }

 private:
  // Projects world points; false if any lies behind the camera.
  bool project(const Eigen::Isometry3d& X_CW, const std::vector<Eigen::Vector3d>& p_W,
               std::vector<cv::Point2d>& px) const {
    std::vector<cv::Point3d> p_C;
    for (const auto& p : p_W) {
      const Eigen::Vector3d c = X_CW * p;
      if (c.z() < 0.05) return false;
      p_C.emplace_back(c.x(), c.y(), c.z());
    }
    cv::projectPoints(p_C, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, dist_, px);
    return true;
  }

  void fill(cv::Mat& img, const std::vector<cv::Point2d>& q, const cv::Scalar& colour) const {
    constexpr int kShift = 4;
    std::vector<cv::Point> p;
    for (const auto& v : q) {
      if (std::abs(v.x) > 1e5 || std::abs(v.y) > 1e5) return;
      p.emplace_back(static_cast<int>(std::lround(v.x * (1 << kShift))),
                     static_cast<int>(std::lround(v.y * (1 << kShift))));
    }
    cv::fillConvexPoly(img, p, colour, cv::LINE_AA, kShift);
  }

  // Area-exact anti-aliasing for the small shapes whose centroids matter (tags): the polygon
  // is filled without anti-aliasing at 8x resolution in its bounding box, averaged down
  // (coverage) and blended. (OpenCV's LINE_AA fill is biased by about half a pixel.)
  void fill_exact(cv::Mat& img, const std::vector<cv::Point2d>& q, const cv::Scalar& colour) const {
    constexpr int kSs = 8, kShift = 4;
    // A vertex far off the picture (a point behind the camera projects anywhere): drawn as
    // fill() draws it, which skips it. Checked first because boundingRect rounds to int, and a
    // rectangle at x = INT_MIN moved by (-1, -1) overflows (UBSan).
    for (const auto& v : q) {
      if (!(std::abs(v.x) <= 1e5 && std::abs(v.y) <= 1e5)) return fill(img, q, colour);
    }
    std::vector<cv::Point2f> qf(q.begin(), q.end());
    const cv::Rect roi = (cv::boundingRect(qf) + cv::Size(2, 2) - cv::Point(1, 1)) & cv::Rect(0, 0, img.cols, img.rows);
    if (roi.empty() || roi.area() > 200 * 200) return fill(img, q, colour);
    cv::Mat fine(roi.height * kSs, roi.width * kSs, CV_8UC1, cv::Scalar(0));
    std::vector<cv::Point> p;
    for (const auto& v : q) {  // 1x x -> 8x (x - roi.x + 0.5) * 8 - 0.5
      p.emplace_back(static_cast<int>(std::lround(((v.x - roi.x + 0.5) * kSs - 0.5) * (1 << kShift))),
                     static_cast<int>(std::lround(((v.y - roi.y + 0.5) * kSs - 0.5) * (1 << kShift))));
    }
    cv::fillConvexPoly(fine, p, cv::Scalar(255), cv::LINE_8, kShift);
    cv::Mat cover;
    cv::resize(fine, cover, roi.size(), 0, 0, cv::INTER_AREA);
    for (int r = 0; r < roi.height; ++r) {
      for (int c = 0; c < roi.width; ++c) {
        const double a = cover.at<uchar>(r, c) / 255.0;
        if (a <= 0.0) continue;
        cv::Vec3b& px = img.at<cv::Vec3b>(roi.y + r, roi.x + c);
        for (int ch = 0; ch < 3; ++ch) {
          px[ch] = cv::saturate_cast<uchar>((1.0 - a) * px[ch] + a * colour[ch]);
        }
      }
    }
  }

  // A rectangle in the shelf's y-z plane at depth x_S: centre (y, z), size (w, h).
  void rect_yz(cv::Mat& img, const DrawnShelf& s, const Eigen::Isometry3d& X_CW, double x,
               double y, double z, double w, double h, const cv::Scalar& colour,
               bool exact = false) const {
    std::vector<cv::Point2d> px;
    if (project(X_CW, {shelf_to_world(s, {x, y + w / 2, z - h / 2}), shelf_to_world(s, {x, y - w / 2, z - h / 2}),
                       shelf_to_world(s, {x, y - w / 2, z + h / 2}), shelf_to_world(s, {x, y + w / 2, z + h / 2})},
                px)) {
      exact ? fill_exact(img, px, colour) : fill(img, px, colour);
    }
  }

  void draw_marker(cv::Mat& img, const DrawnShelf& s, const Eigen::Isometry3d& X_CW, double x,
                   double y, double z, int id, double brightness) const {
    // White sheet of 8 units: 1 unit quiet zone, the 6-unit marker (4x4 bits + black border).
    const double unit = s.geometry.marker_size_m / 6.0, half = 4.0 * unit;
    std::vector<cv::Point2d> px;
    if (!project(X_CW, {shelf_to_world(s, {x, y + half, z + half}), shelf_to_world(s, {x, y - half, z + half}),
                        shelf_to_world(s, {x, y - half, z - half}), shelf_to_world(s, {x, y + half, z - half})},
                 px)) {
      return;
    }
    const int side = 160, quiet = side / 8;
    cv::Mat marker, sheet(side, side, CV_8UC1, cv::Scalar(255));
    const auto dict = cv::aruco::getPredefinedDictionary(*aruco_dictionary_id(s.geometry.aruco_dictionary));
    cv::aruco::drawMarker(dict, id, side - 2 * quiet, marker, 1);
    marker.copyTo(sheet(cv::Rect(quiet, quiet, side - 2 * quiet, side - 2 * quiet)));
    cv::Mat sheet_bgr;
    cv::cvtColor(sheet, sheet_bgr, cv::COLOR_GRAY2BGR);
    sheet_bgr *= brightness;
    const std::vector<cv::Point2f> src{{0, 0}, {side - 1.f, 0}, {side - 1.f, side - 1.f}, {0, side - 1.f}};
    std::vector<cv::Point2f> dst(px.begin(), px.end());
    const cv::Rect roi = cv::boundingRect(dst) & cv::Rect(0, 0, img.cols, img.rows);
    if (roi.empty()) return;
    for (auto& d : dst) d -= cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
    const cv::Mat H = cv::getPerspectiveTransform(src, dst);
    cv::Mat warped, mask;
    cv::warpPerspective(sheet_bgr, warped, H, roi.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::warpPerspective(cv::Mat(side, side, CV_8UC1, cv::Scalar(255)), mask, H, roi.size(),
                        cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    warped.copyTo(img(roi), mask);
  }

  void draw_shelf(cv::Mat& img, const Scene& scene, const DrawnShelf& s,
                  const Eigen::Isometry3d& X_CW) const {
    const KnownShelf& g = s.geometry;
    const double b = scene.brightness;
    const int nc = g.columns(), nr = g.levels();
    // Boxes (behind the front bars): front face at x_S = (depth - box) / 2.
    for (const DrawnBox& box : s.boxes) {
      const double y = 0.5 * (post_y(s, box.column - 1) + post_y(s, box.column));
      const double floor = beam_z(s, box.level - 1) + 0.5 * g.beam_thickness_m;
      const double x = 0.5 * (g.depth_m - s.box_size_m);
      rect_yz(img, s, X_CW, x, y, floor + 0.5 * s.box_size_m, s.box_size_m, s.box_size_m, scene.box_bgr * b);
      draw_marker(img, s, X_CW, x - 1e-3, y, floor + 0.5 * s.box_size_m, box.id, b);
    }
    // Front posts and beams.
    const double top = beam_z(s, nr), bottom = beam_z(s, 0);
    const double left = post_y(s, 0), right = post_y(s, nc);
    for (int i = 0; i <= nc; ++i) {
      rect_yz(img, s, X_CW, 0.0, post_y(s, i), 0.5 * top, g.post_thickness_m, top, scene.bar_bgr * b);
    }
    for (int j = 0; j <= nr; ++j) {
      rect_yz(img, s, X_CW, 0.0, 0.5 * (left + right), beam_z(s, j), left - right + g.post_thickness_m,
              g.beam_thickness_m, scene.bar_bgr * b);
    }
    (void)bottom;
    // Tags on the outer surface of the front bars.
    for (int i = 0; i <= nc; ++i) {
      for (int j = 0; j <= nr; ++j) {
        rect_yz(img, s, X_CW, -g.tag_offset_m, post_y(s, i), beam_z(s, j), g.tag_size_m, g.tag_size_m,
                scene.tag_bgr * b, true);
      }
    }
  }

  CameraIntrinsics k_;
  cv::Matx33d K_;
  cv::Vec<double, 5> dist_{0, 0, 0, 0, 0};
};

}  // namespace shelfcross::flight_sw::testing
