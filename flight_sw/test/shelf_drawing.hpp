#pragma once
// Test helper: draws shelves as the Tello's camera would see them, with plain OpenCV (the
// flight software's tests may not use render/). Tags are filled squares in the tag colour at
// the projected post/beam intersections, boxes are brown front faces carrying an ArUco marker
// (cv::aruco::drawMarker on a white sheet, warped onto the projected face), posts and beams
// are dark blue bars, the background a grey wall. Points go through cv::projectPoints, with
// the lens distortion when asked. Painter's order: farthest shelf first.

#include <algorithm>
#include <array>
#include <map>
#include <string>
#include <tuple>
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

/// The orientation of shelf frame S in the world: a turn about z by the shelf's yaw.
inline Eigen::Matrix3d shelf_rotation_W(const DrawnShelf& s) {
  return Eigen::AngleAxisd(s.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

/// A point of shelf frame S in the world, with S's orientation R_WS (shelf_rotation_W: taken
/// once where many points are moved).
inline Eigen::Vector3d shelf_to_world(const DrawnShelf& s, const Eigen::Matrix3d& R_WS, const Eigen::Vector3d& p_S) {
  return s.origin_W_m + R_WS * p_S;
}

/// A point of shelf frame S in the world.
inline Eigen::Vector3d shelf_to_world(const DrawnShelf& s, const Eigen::Vector3d& p_S) {
  return shelf_to_world(s, shelf_rotation_W(s), p_S);
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
    cv::Mat img;
    draw(scene, X_WC, img);
    return img;
  }

  /// The same picture drawn into `img`, allocated only when its size or type differ: a caller
  /// drawing a picture per frame reuses its buffer.
  void draw(const Scene& scene, const Eigen::Isometry3d& X_WC, cv::Mat& img) const {
    const cv::Scalar wall_bgr = scene.wall_bgr * scene.brightness;
    if (wall_.empty() || wall_bgr != wall_bgr_) {
      wall_.create(k_.height_px, k_.width_px, CV_8UC3);
      wall_ = wall_bgr;
      wall_bgr_ = wall_bgr;
    }
    wall_.copyTo(img);
    const Eigen::Isometry3d X_CW = X_WC.inverse();
    std::vector<const DrawnShelf*> order;
    for (const auto& s : scene.shelves) order.push_back(&s);
    std::sort(order.begin(), order.end(), [&](const DrawnShelf* a, const DrawnShelf* c) {
      return (a->origin_W_m - X_WC.translation()).norm() > (c->origin_W_m - X_WC.translation()).norm();
    });
    for (const DrawnShelf* s : order) draw_shelf(img, scene, *s, X_CW);
  }

 private:
  // How a shape is painted: filled (anti-aliased edges), filled area-exact (fill_exact), or a
  // box's marker sheet warped onto it.
  enum class Paint { fill, exact, marker };
  // A quadrilateral on a shelf: its corners in the shelf's frame S and its paint.
  struct Shape {
    std::array<Eigen::Vector3d, 4> p_S;
    Paint paint = Paint::fill;
    cv::Scalar colour;
    int marker_id = 0;
  };

  // A rectangle in the shelf's y-z plane at depth x_S: centre (y, z), size (w, h).
  static Shape rect_yz(double x, double y, double z, double w, double h, const cv::Scalar& colour, Paint paint) {
    return {{Eigen::Vector3d(x, y + w / 2, z - h / 2), Eigen::Vector3d(x, y - w / 2, z - h / 2),
             Eigen::Vector3d(x, y - w / 2, z + h / 2), Eigen::Vector3d(x, y + w / 2, z + h / 2)},
            paint, colour};
  }

  // The top-left rows x cols of `buffer`, grown when too small: scratch pictures reuse their
  // memory from shape to shape (a fresh one per shape costs more than drawing it).
  static cv::Mat scratch(cv::Mat& buffer, int rows, int cols, int type) {
    if (buffer.type() != type || buffer.rows < rows || buffer.cols < cols) {
      buffer.create(std::max(rows, buffer.rows), std::max(cols, buffer.cols), type);
    }
    return buffer(cv::Rect(0, 0, cols, rows));
  }

  void fill(cv::Mat& img, const cv::Point2d* q, const cv::Scalar& colour) const {
    constexpr int kShift = 4;
    points_.clear();
    for (int k = 0; k < 4; ++k) {
      const cv::Point2d& v = q[k];
      if (std::abs(v.x) > 1e5 || std::abs(v.y) > 1e5) return;
      points_.emplace_back(static_cast<int>(std::lround(v.x * (1 << kShift))),
                           static_cast<int>(std::lround(v.y * (1 << kShift))));
    }
    cv::fillConvexPoly(img, points_, colour, cv::LINE_AA, kShift);
  }

  // Area-exact anti-aliasing for the small shapes whose centroids matter (tags): the polygon
  // is filled without anti-aliasing at 8x resolution in its bounding box, averaged down
  // (coverage) and blended. (OpenCV's LINE_AA fill is biased by about half a pixel.)
  void fill_exact(cv::Mat& img, const cv::Point2d* q, const cv::Scalar& colour) const {
    constexpr int kSs = 8, kShift = 4;
    // A vertex far off the picture (a point behind the camera projects anywhere): drawn as
    // fill() draws it, which skips it. Checked first because boundingRect rounds to int, and a
    // rectangle at x = INT_MIN moved by (-1, -1) overflows (UBSan).
    for (int k = 0; k < 4; ++k) {
      if (!(std::abs(q[k].x) <= 1e5 && std::abs(q[k].y) <= 1e5)) return fill(img, q, colour);
    }
    const std::array<cv::Point2f, 4> qf{q[0], q[1], q[2], q[3]};
    const cv::Rect roi = (cv::boundingRect(qf) + cv::Size(2, 2) - cv::Point(1, 1)) & cv::Rect(0, 0, img.cols, img.rows);
    if (roi.empty() || roi.area() > 200 * 200) return fill(img, q, colour);
    cv::Mat fine = scratch(fine_, roi.height * kSs, roi.width * kSs, CV_8UC1);
    fine = cv::Scalar(0);
    points_.clear();
    for (int k = 0; k < 4; ++k) {  // 1x x -> 8x (x - roi.x + 0.5) * 8 - 0.5
      const cv::Point2d& v = q[k];
      points_.emplace_back(static_cast<int>(std::lround(((v.x - roi.x + 0.5) * kSs - 0.5) * (1 << kShift))),
                           static_cast<int>(std::lround(((v.y - roi.y + 0.5) * kSs - 0.5) * (1 << kShift))));
    }
    cv::fillConvexPoly(fine, points_, cv::Scalar(255), cv::LINE_8, kShift);
    cv::Mat cover = scratch(cover_, roi.height, roi.width, CV_8UC1);
    cv::resize(fine, cover, roi.size(), 0, 0, cv::INTER_AREA);
    // Wholly covered: (1 - 1) px + 1 colour is the colour itself.
    const cv::Vec3b covered(cv::saturate_cast<uchar>(colour[0]), cv::saturate_cast<uchar>(colour[1]),
                            cv::saturate_cast<uchar>(colour[2]));
    for (int r = 0; r < roi.height; ++r) {
      const uchar* cover_row = cover.ptr<uchar>(r);
      cv::Vec3b* img_row = img.ptr<cv::Vec3b>(roi.y + r) + roi.x;
      for (int c = 0; c < roi.width; ++c) {
        if (cover_row[c] == 0) continue;
        if (cover_row[c] == 255) {
          img_row[c] = covered;
          continue;
        }
        const double a = cover_row[c] / 255.0;
        cv::Vec3b& px = img_row[c];
        for (int ch = 0; ch < 3; ++ch) {
          px[ch] = cv::saturate_cast<uchar>((1.0 - a) * px[ch] + a * colour[ch]);
        }
      }
    }
  }

  // A box's marker: its white sheet warped onto the projected corners q.
  void draw_marker(cv::Mat& img, const cv::Point2d* q, const cv::Mat& sheet_bgr) const {
    const float side = static_cast<float>(sheet_bgr.cols);
    const std::array<cv::Point2f, 4> src{{{0, 0}, {side - 1.f, 0}, {side - 1.f, side - 1.f}, {0, side - 1.f}}};
    std::array<cv::Point2f, 4> dst{q[0], q[1], q[2], q[3]};
    const cv::Rect roi = cv::boundingRect(dst) & cv::Rect(0, 0, img.cols, img.rows);
    if (roi.empty()) return;
    for (auto& d : dst) d -= cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
    const cv::Mat H = cv::getPerspectiveTransform(src.data(), dst.data());
    // Every pixel of both is written (BORDER_CONSTANT outside the sheet): scratch serves.
    cv::Mat warped = scratch(warped_, roi.height, roi.width, CV_8UC3);
    cv::Mat mask = scratch(mask_, roi.height, roi.width, CV_8UC1);
    cv::warpPerspective(sheet_bgr, warped, H, roi.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    if (sheet_mask_.size() != sheet_bgr.size()) sheet_mask_ = cv::Mat(sheet_bgr.size(), CV_8UC1, cv::Scalar(255));
    cv::warpPerspective(sheet_mask_, mask, H, roi.size(), cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    warped.copyTo(img(roi), mask);
  }

  // The white sheet of a marker, drawn once per (dictionary, id, brightness): 8 units of
  // 20 px, a 1-unit quiet zone around the 6-unit marker (4x4 bits and the black border).
  const cv::Mat& marker_sheet(const std::string& dictionary, int id, double brightness) const {
    const auto key = std::make_tuple(dictionary, id, brightness);
    auto it = sheets_.find(key);
    if (it != sheets_.end()) return it->second;
    const int side = 160, quiet = side / 8;
    cv::Mat marker, sheet(side, side, CV_8UC1, cv::Scalar(255));
    const auto dict = cv::aruco::getPredefinedDictionary(*aruco_dictionary_id(dictionary));
    cv::aruco::drawMarker(dict, id, side - 2 * quiet, marker, 1);
    marker.copyTo(sheet(cv::Rect(quiet, quiet, side - 2 * quiet, side - 2 * quiet)));
    cv::Mat sheet_bgr;
    cv::cvtColor(sheet, sheet_bgr, cv::COLOR_GRAY2BGR);
    sheet_bgr *= brightness;
    return sheets_.emplace(key, std::move(sheet_bgr)).first->second;
  }

  // The shelf's shapes in painter's order: boxes and their markers (behind the front bars),
  // the front posts and beams, the tags on the bars' outer surface.
  void shelf_shapes(const Scene& scene, const DrawnShelf& s) const {
    const KnownShelf& g = s.geometry;
    const double b = scene.brightness;
    const int nc = g.columns(), nr = g.levels();
    shapes_.clear();
    for (const DrawnBox& box : s.boxes) {  // front face at x_S = (depth - box) / 2
      const double y = 0.5 * (post_y(s, box.column - 1) + post_y(s, box.column));
      const double floor = beam_z(s, box.level - 1) + 0.5 * g.beam_thickness_m;
      const double x = 0.5 * (g.depth_m - s.box_size_m);
      const double z = floor + 0.5 * s.box_size_m;
      shapes_.push_back(rect_yz(x, y, z, s.box_size_m, s.box_size_m, scene.box_bgr * b, Paint::fill));
      // The sheet, 8 marker units square, 1 mm in front of the face.
      const double half = 4.0 * (g.marker_size_m / 6.0), xm = x - 1e-3;
      shapes_.push_back({{Eigen::Vector3d(xm, y + half, z + half), Eigen::Vector3d(xm, y - half, z + half),
                          Eigen::Vector3d(xm, y - half, z - half), Eigen::Vector3d(xm, y + half, z - half)},
                         Paint::marker, cv::Scalar(), box.id});
    }
    const double top = beam_z(s, nr);
    const double left = post_y(s, 0), right = post_y(s, nc);
    for (int i = 0; i <= nc; ++i) {
      shapes_.push_back(rect_yz(0.0, post_y(s, i), 0.5 * top, g.post_thickness_m, top, scene.bar_bgr * b, Paint::fill));
    }
    for (int j = 0; j <= nr; ++j) {
      shapes_.push_back(rect_yz(0.0, 0.5 * (left + right), beam_z(s, j), left - right + g.post_thickness_m,
                                g.beam_thickness_m, scene.bar_bgr * b, Paint::fill));
    }
    for (int i = 0; i <= nc; ++i) {
      for (int j = 0; j <= nr; ++j) {
        shapes_.push_back(rect_yz(-g.tag_offset_m, post_y(s, i), beam_z(s, j), g.tag_size_m, g.tag_size_m,
                                  scene.tag_bgr * b, Paint::exact));
      }
    }
  }

  // The shelf's shapes projected in one pass (each point projects on its own), then painted in
  // order; a shape with a corner less than 5 cm in front of the camera is left out.
  void draw_shelf(cv::Mat& img, const Scene& scene, const DrawnShelf& s, const Eigen::Isometry3d& X_CW) const {
    shelf_shapes(scene, s);
    const Eigen::Matrix3d R_WS = shelf_rotation_W(s);
    p_C_.clear();
    visible_.assign(shapes_.size(), false);
    for (size_t k = 0; k < shapes_.size(); ++k) {
      std::array<cv::Point3d, 4> corners_C;
      bool in_front = true;
      for (size_t i = 0; i < 4 && in_front; ++i) {
        const Eigen::Vector3d c = X_CW * shelf_to_world(s, R_WS, shapes_[k].p_S[i]);
        in_front = c.z() >= 0.05;
        corners_C[i] = cv::Point3d(c.x(), c.y(), c.z());
      }
      if (!in_front) continue;
      visible_[k] = true;
      p_C_.insert(p_C_.end(), corners_C.begin(), corners_C.end());
    }
    if (p_C_.empty()) return;
    cv::projectPoints(p_C_, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, dist_, px_);
    const cv::Point2d* q = px_.data();
    for (size_t k = 0; k < shapes_.size(); ++k) {
      if (!visible_[k]) continue;
      const Shape& shape = shapes_[k];
      switch (shape.paint) {
        case Paint::fill: fill(img, q, shape.colour); break;
        case Paint::exact: fill_exact(img, q, shape.colour); break;
        case Paint::marker:
          draw_marker(img, q, marker_sheet(s.geometry.aruco_dictionary, shape.marker_id, scene.brightness));
          break;
      }
      q += 4;
    }
  }

  CameraIntrinsics k_;
  cv::Matx33d K_;
  cv::Vec<double, 5> dist_{0, 0, 0, 0, 0};
  // Drawing's scratch, reused (a Drawer draws one picture at a time): allocations cost more
  // than most shapes.
  mutable cv::Mat wall_;  ///< the bare wall, in wall_bgr_
  mutable cv::Scalar wall_bgr_;
  mutable cv::Mat fine_, cover_, warped_, mask_, sheet_mask_;
  mutable std::map<std::tuple<std::string, int, double>, cv::Mat> sheets_;
  mutable std::vector<Shape> shapes_;
  mutable std::vector<bool> visible_;
  mutable std::vector<cv::Point3d> p_C_;
  mutable std::vector<cv::Point2d> px_;
  mutable std::vector<cv::Point> points_;
};

}  // namespace shelfcross::flight_sw::testing
