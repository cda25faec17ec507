// Perception: eq. 1 (front shelf), eq. 2-4 (stair classification and its limits), tags under
// lighting changes, on synthetic drawn images.

#include <cmath>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include <gtest/gtest.h>

#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/perception/box_tracker.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/test/shelf_drawing.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {
namespace {

constexpr double kDeg = deg_to_rad(1.0);  // one degree

TEST(GridLimits, Eq3Eq4HandComputedWideColumns) {
  // w = 0.48 > h = 0.34: sqrt(w^2 + h^2) = 0.588218...
  const GridLimits l = grid_limits(0.48, 0.34);
  EXPECT_NEAR(l.dx_lim_px, 0.34 * 0.34 / 0.5882176467, 1e-9);  // 0.196526
  EXPECT_NEAR(l.dx_lim_px, 0.196526, 1e-6);
  EXPECT_NEAR(l.dy_lim_px, 0.277448, 1e-6);                    // 0.48 * 0.34 / 0.588218
  EXPECT_NEAR(l.theta_lim_rad, 35.3112 * kDeg, 1e-6);          // atan(0.34 / 0.48)
}

TEST(GridLimits, Eq3Eq4HandComputedTallRowsAndSquare) {
  const GridLimits l = grid_limits(0.3, 0.4);  // w < h, sqrt = 0.5
  EXPECT_NEAR(l.dx_lim_px, 0.24, 1e-12);       // 0.3 * 0.4 / 0.5
  EXPECT_NEAR(l.dy_lim_px, 0.18, 1e-12);       // 0.3^2 / 0.5
  EXPECT_NEAR(l.theta_lim_rad, std::atan(0.75), 1e-12);
  const GridLimits s = grid_limits(2.0, 2.0);
  EXPECT_NEAR(s.dx_lim_px, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.dy_lim_px, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.theta_lim_rad, M_PI / 4.0, 1e-12);
}

TEST(GridLimits, NonUniformShelfUsesLargestPitchesAndSmallerNeighbours) {
  KnownShelf paper;  // columns 0.34/0.48, rows 0.34
  const GridLimits l = grid_limits(paper, 100.0);
  EXPECT_NEAR(l.dx_lim_px, 19.6526, 1e-3);
  EXPECT_NEAR(l.dy_lim_px, 27.7448, 1e-3);
  EXPECT_NEAR(l.theta_lim_rad, 35.3112 * kDeg, 1e-6);
  // Rows of 0.2 m under columns of 0.5 m: the flattest diagonal is the 0.2 m row's over the
  // 0.5 m column, theta_L = atan(0.2 / 0.5) = 21.8 deg (eq. 3 with the largest pitches alone
  // put the row window, 0.31 m, above the 0.2 m row: no rotation at all was classified).
  KnownShelf mixed;
  mixed.column_pitch_m = {0.5, 0.5};
  mixed.row_pitch_m = {0.4, 0.2};
  const GridLimits m = grid_limits(mixed, 1.0);
  EXPECT_NEAR(m.theta_lim_rad, std::atan(0.2 / 0.5), 1e-12);
  EXPECT_NEAR(m.dy_lim_px, 0.5 * std::sin(std::atan(0.2 / 0.5)), 1e-12);
  EXPECT_NEAR(m.dx_lim_px, 0.4 * std::sin(std::atan(0.2 / 0.5)), 1e-12);
  EXPECT_LT(m.dy_lim_px, 0.2 * std::cos(m.theta_lim_rad) + 1e-12);  // the next row stays out
}

// A grid of posts x beams in metres, scaled to pixels and rotated by theta in the image.
struct Points {
  std::vector<cv::Point2d> px;
  std::vector<int> row, column;
};
Points rotated_grid(const KnownShelf& s, double theta_rad, double px_per_m) {
  Points g;
  const cv::Point2d centre(480, 360);
  for (int j = 0; j <= s.levels(); ++j) {
    for (int i = 0; i <= s.columns(); ++i) {
      const cv::Point3d p = grid_tag_G(s, i, j);
      // Image x = -y_G (left is +y), image y = -z_G (up is +z); then rotate.
      const double x = -p.y * px_per_m, y = -p.z * px_per_m;
      g.px.push_back(centre + cv::Point2d(std::cos(theta_rad) * x - std::sin(theta_rad) * y,
                                          std::sin(theta_rad) * x + std::cos(theta_rad) * y));
      g.row.push_back(j);
      g.column.push_back(i);
    }
  }
  return g;
}

void expect_classification(const KnownShelf& s, double theta_rad, bool valid) {
  const double scale = 300.0;
  const Points g = rotated_grid(s, theta_rad, scale);
  const GridLimits lim = grid_limits(s, scale);
  const TagGrid grid = classify_grid(g.px, lim, 0.17);
  SCOPED_TRACE("theta " + std::to_string(theta_rad / kDeg) + " deg, limit " +
               std::to_string(lim.theta_lim_rad / kDeg) + " deg: " + grid.refusal);
  ASSERT_EQ(grid.valid, valid);
  if (!valid) return;
  EXPECT_EQ(grid.rows, s.levels() + 1);
  EXPECT_EQ(grid.columns, s.columns() + 1);
  for (size_t k = 0; k < g.px.size(); ++k) {
    EXPECT_EQ(grid.row[k], g.row[k]);
    EXPECT_EQ(grid.column[k], g.column[k]);
  }
}

KnownShelf shelf_of(std::vector<double> cols, std::vector<double> rows) {
  KnownShelf s;
  s.column_pitch_m = std::move(cols);
  s.row_pitch_m = std::move(rows);
  return s;
}

TEST(StairClassification, LabelsUpToJustUnderTheLimitAndRefusesBeyond) {
  const std::vector<KnownShelf> shelves = {
      KnownShelf{},                                  // the paper's shelf: 34/48 columns
      shelf_of({0.4, 0.4, 0.4}, {0.4, 0.4}),         // square cells: limit 45 deg
      shelf_of({0.5, 0.5, 0.5, 0.5}, {0.3, 0.3, 0.3}),  // wide cells (w > h)
      shelf_of({0.3, 0.3, 0.3}, {0.45, 0.45, 0.45}),    // tall cells (w < h)
      shelf_of({0.36, 0.52, 0.40}, {0.30, 0.38, 0.34, 0.42, 0.30}),  // scenarios/stress/grid_5x3_yellow.yaml
      shelf_of({0.34, 0.48, 0.40, 0.34, 0.48, 0.40}, {0.30, 0.34, 0.30, 0.38, 0.30, 0.34}),  // grid_6x6_mixed
  };
  for (const KnownShelf& s : shelves) {
    const double limit = grid_limits(s, 1.0).theta_lim_rad;
    for (double sign : {1.0, -1.0}) {
      for (double theta : {0.0, 5 * kDeg, 15 * kDeg, limit - 2 * kDeg, limit - 0.3 * kDeg}) {
        expect_classification(s, sign * theta, true);
      }
      if (limit < 44 * kDeg) {  // past 45 deg a square grid is itself again, rotated by 90
        for (double theta : {limit + 0.5 * kDeg, limit + 3 * kDeg, limit + 8 * kDeg}) {
          expect_classification(s, sign * theta, false);
        }
      }
    }
  }
}

TEST(StairClassification, RefusesDuplicatesAndReportsEmpty) {
  EXPECT_FALSE(classify_grid({}, grid_limits(10, 10), 0.17).valid);
  const TagGrid one = classify_grid({{5, 5}}, grid_limits(10, 10), 0.17);
  EXPECT_TRUE(one.valid);
  EXPECT_EQ(one.rows, 1);
  EXPECT_EQ(one.columns, 1);
}

TEST(FrontShelf, Eq1AreaRatioKeepsOnlyTheFrontShelf) {
  KnownShelf known;
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf({3.0, 0.0, 0.0}), testing::paper_shelf({5.5, 0.2, 0.0})};
  const CameraIntrinsics k;
  const testing::Drawer drawer(k, true);
  for (double roll : {0.0, 8 * kDeg}) {
    for (double pitch : {0.0, 4 * kDeg}) {
      const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({0.3, 0.05, 0.98}, 0.03, pitch, roll));
      PerceptionParams p;
      TagDetector det(p);
      std::vector<TagBlob> all;
      det.detect(img, cv::Rect(0, 0, img.cols, img.rows), all);
      std::vector<TagBlob> front = all;
      keep_front_shelf(front, p.area_ratio_threshold);
      // Some tags of the shelf behind show between the bars; eq. 1 drops exactly those.
      EXPECT_GT(all.size(), 25u) << "the test needs tags of the shelf behind in view";
      ASSERT_EQ(front.size(), 25u);
      FlightConfig config;
      ShelfView view;
      analyse_shelf(img, det, config, view);
      EXPECT_TRUE(view.full) << view.grid.refusal;
    }
  }
}

TEST(Tags, DetectedUnderDimLightAndHueWrap) {
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf()};
  const CameraIntrinsics k;
  const testing::Drawer drawer(k, false);
  for (double brightness : {1.0, 0.45}) {
    scene.brightness = brightness;
    const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({0.9, 0.0, 0.98}, 0.0));
    TagDetector det{PerceptionParams{}};
    std::vector<TagBlob> tags;
    det.detect(img, cv::Rect(0, 0, img.cols, img.rows), tags);
    EXPECT_EQ(tags.size(), 25u) << "brightness " << brightness;
  }
  // Red tags: the hue range wraps through 0.
  scene.brightness = 1.0;
  scene.tag_bgr = cv::Scalar(40, 30, 210);
  const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({0.9, 0.0, 0.98}, 0.0));
  PerceptionParams red;
  red.tag_hsv.hue_min = 170;
  red.tag_hsv.hue_max = 8;
  TagDetector det(red);
  std::vector<TagBlob> tags;
  det.detect(img, cv::Rect(0, 0, img.cols, img.rows), tags);
  EXPECT_EQ(tags.size(), 25u);
}

TEST(StairClassification, DrawnShelfRolledUnderAndPastTheLimit) {
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf()};
  const CameraIntrinsics k;
  const testing::Drawer drawer(k, true);
  FlightConfig config;
  TagDetector det(config.perception);
  for (double roll_deg : {-25.0, 0.0, 12.0, 25.0}) {
    const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({0.0, 0.0, 0.98}, 0.0, 0.0, roll_deg * kDeg));
    ShelfView view;
    analyse_shelf(img, det, config, view);
    ASSERT_TRUE(view.full) << roll_deg << ": " << view.grid.refusal;
    // Tag (row j, column i) must be where the projection of post i, beam j is.
    for (int j = 0; j <= 4; ++j) {
      for (int i = 0; i <= 4; ++i) {
        const TagBlob& t = view.tags[static_cast<size_t>(view.grid.at(j, i))];
        const Eigen::Isometry3d X_CW =
            testing::camera_pose_W({0.0, 0.0, 0.98}, 0.0, 0.0, roll_deg * kDeg).inverse();
        const Eigen::Vector3d c = X_CW * testing::shelf_to_world(scene.shelves[0],
                                                                 {-0.01, testing::post_y(scene.shelves[0], i),
                                                                  testing::beam_z(scene.shelves[0], j)});
        std::vector<cv::Point2d> px;
        cv::projectPoints(std::vector<cv::Point3d>{{c.x(), c.y(), c.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                          cv::Matx33d(k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1),
                          cv::Vec<double, 5>(k.k1, k.k2, k.p1, k.p2, k.k3), px);
        EXPECT_LT(cv::norm(px[0] - t.centre_px), 1.0) << "row " << j << " column " << i;
      }
    }
  }
  // Rolled 40 deg, past the 35.3 deg limit of this shelf: refused, not guessed.
  const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({-0.2, 0.0, 0.98}, 0.0, 0.0, 40 * kDeg));
  ShelfView view;
  analyse_shelf(img, det, config, view);
  EXPECT_EQ(view.tags.size(), 25u);
  EXPECT_FALSE(view.grid.valid);
  EXPECT_FALSE(view.full);
}


// ---- The fast pipeline against the reference ----

PerceptionParams with_pipeline(PerceptionParams p, PerceptionPipeline pipeline) {
  p.pipeline = pipeline;
  return p;
}

// The fused colour test is OpenCV's BGR->HSV + inRange, bit for bit, on every 24-bit colour,
// for the default green window and a window wrapping through red.
TEST(FastTags, ColourTestEqualsCvtColorAndInRangeOnEveryColour) {
  cv::Mat bgr(4096, 4096, CV_8UC3);
  for (int i = 0; i < 1 << 24; ++i) {
    cv::Vec3b& p = bgr.at<cv::Vec3b>(i >> 12, i & 4095);
    p = cv::Vec3b(static_cast<uchar>(i >> 16), static_cast<uchar>(i >> 8), static_cast<uchar>(i));
  }
  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  PerceptionParams red;
  red.tag_hsv = {170, 8, 60, 250, 20, 240};
  for (const PerceptionParams& params : {PerceptionParams{}, red}) {
    const HsvRange& r = params.tag_hsv;
    cv::Mat mask, wrap;
    if (r.hue_min <= r.hue_max) {
      cv::inRange(hsv, cv::Scalar(r.hue_min, r.sat_min, r.val_min), cv::Scalar(r.hue_max, r.sat_max, r.val_max), mask);
    } else {
      cv::inRange(hsv, cv::Scalar(r.hue_min, r.sat_min, r.val_min), cv::Scalar(179, r.sat_max, r.val_max), mask);
      cv::inRange(hsv, cv::Scalar(0, r.sat_min, r.val_min), cv::Scalar(r.hue_max, r.sat_max, r.val_max), wrap);
      mask |= wrap;
    }
    const TagDetector det(params);
    int differ = 0, tag_colours = 0;
    for (int y = 0; y < bgr.rows; ++y) {
      const uchar* m = mask.ptr<uchar>(y);
      const uchar* p = bgr.ptr<uchar>(y);
      for (int x = 0; x < bgr.cols; ++x) {
        const bool fast = det.is_tag_colour(p + 3 * x);
        differ += fast != (m[x] != 0);
        tag_colours += fast;
      }
    }
    EXPECT_EQ(differ, 0) << "hue " << r.hue_min << ".." << r.hue_max;
    EXPECT_GT(tag_colours, 100000);
  }
}

void expect_same_blobs(const std::vector<TagBlob>& a, const std::vector<TagBlob>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].centre_px, b[i].centre_px) << what << " blob " << i;  // bit-exact, same order
    EXPECT_EQ(a[i].area_px, b[i].area_px) << what << " blob " << i;
    EXPECT_EQ(a[i].bbox_px, b[i].bbox_px) << what << " blob " << i;
  }
}

// Same blobs (centroids bit-exact, same order) as cvtColor + inRange + connected components,
// on whole frames with sensor-like noise, a shelf behind, dim light, and in windows cut
// through tags, at the seed strides the flight software uses.
TEST(FastTags, SameBlobsAsTheReferenceDetector) {
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf({3.0, 0.0, 0.0}), testing::paper_shelf({5.5, 0.2, 0.0})};
  const CameraIntrinsics k;
  const testing::Drawer drawer(k, true);
  cv::RNG rng(7);
  TagDetector ref(with_pipeline({}, PerceptionPipeline::reference));
  TagDetector fast(with_pipeline({}, PerceptionPipeline::fast));
  int compared = 0;
  for (double brightness : {1.0, 0.5}) {
    scene.brightness = brightness;
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.05, 0.98), Eigen::Vector3d(1.6, -0.1, 0.9),
                                     Eigen::Vector3d(2.3, -0.15, 0.8)}) {
      cv::Mat img = drawer.draw(scene, testing::camera_pose_W(p, 0.04, 0.02, 0.05));
      cv::Mat noise(img.size(), CV_16SC3);
      rng.fill(noise, cv::RNG::NORMAL, 0, 3);
      img.convertTo(img, CV_16SC3);
      img += noise;
      img.convertTo(img, CV_8UC3);
      for (const cv::Rect& roi : {cv::Rect(0, 0, img.cols, img.rows), cv::Rect(301, 147, 333, 281), cv::Rect(-20, 400, 500, 500)}) {
        for (int stride : {1, 2, 3, 4}) {
          std::vector<TagBlob> a, b;
          ref.detect(img, roi, a);
          fast.detect(img, roi, b, stride);
          std::ostringstream what;
          what << "brightness " << brightness << " x " << p.x() << " roi " << roi << " stride " << stride;
          expect_same_blobs(a, b, what.str());
          compared += static_cast<int>(a.size());
        }
      }
    }
  }
  EXPECT_GT(compared, 500);
}

// Markers read in the cells without corner refinement: the same IDs, centres within 1.5 px
// and areas within 8 % of the reference's full-frame detection; what decides is unchanged: the same cells, and
// areas far from eq. 1's 45 % threshold.
TEST(FastMarkers, SameMarkersInTheCellsAsTheWholeFrameReference) {
  testing::Scene scene;
  testing::DrawnShelf front = testing::paper_shelf({3.0, 0.0, 0.0});
  front.boxes = {{2, 2, 4}, {3, 2, 9}, {3, 3, 17}, {1, 1, 21}, {4, 4, 30}};
  scene.shelves = {front};
  const CameraIntrinsics k;
  const testing::Drawer drawer(k, true);
  FlightConfig config;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.8, 0.0, 0.98), Eigen::Vector3d(0.5, 0.1, 0.95)}) {
    const cv::Mat img = drawer.draw(scene, testing::camera_pose_W(p, 0.0));
    TagDetector det(config.perception);
    ShelfView view;
    analyse_shelf(img, det, config, view);
    ASSERT_TRUE(view.full) << view.grid.refusal;
    cv::Rect grid = view.tags.front().bbox_px;
    for (const TagBlob& t : view.tags) grid |= t.bbox_px;
    MarkerDetector markers(config.shelf.aruco_dictionary);
    std::vector<MarkerSighting> a, b;
    markers.detect(img, a);
    markers.detect_in(img, grid, config.shelf.marker_size_m * view.px_per_m, config.perception.marker_area_ratio_threshold, b);
    ASSERT_EQ(a.size(), 5u);
    ASSERT_EQ(b.size(), a.size());
    for (const MarkerSighting& m : a) {
      const auto same = std::find_if(b.begin(), b.end(), [&](const MarkerSighting& n) { return n.id == m.id; });
      ASSERT_NE(same, b.end()) << "marker " << m.id;
      EXPECT_LT(cv::norm(same->centre_px - m.centre_px), 1.5) << "marker " << m.id;
      EXPECT_NEAR(same->area_px, m.area_px, 0.08 * m.area_px) << "marker " << m.id;
    }
    EXPECT_EQ(assign_markers(view, a, config), assign_markers(view, b, config));
  }
}

TEST(BoxTracker, MovesAtTheMeasuredImageVelocityThenCoasts) {
  BoxTracker t;
  EXPECT_FALSE(t.predict(0));
  t.init({100, 100, 50, 40}, 0);
  EXPECT_EQ(*t.predict(33 * kMs), cv::Rect2d(100, 100, 50, 40));  // one measurement: stays
  t.correct({110, 95, 60, 40}, 100 * kMs);  // centre +15, -5 px; width +10 px in 0.1 s
  const cv::Rect2d p = *t.predict(200 * kMs);
  EXPECT_NEAR(p.x + 0.5 * p.width, 140 + 15, 1e-9);
  EXPECT_NEAR(p.y + 0.5 * p.height, 115 - 5, 1e-9);
  EXPECT_NEAR(p.width, 70, 1e-9);
  EXPECT_NEAR(p.height, 40, 1e-9);
  // Longer than kCoast_s without a measurement: where it was last seen.
  EXPECT_EQ(*t.predict(100 * kMs + seconds_to_ns(BoxTracker::kCoast_s + 0.1)), cv::Rect2d(110, 95, 60, 40));
}

// Pictures of a lossy link arrive in bursts: two a millisecond apart whose boxes differ by a
// few pixels of measurement noise must not throw the prediction hundreds of pixels away (a
// two-point rate would be 6,000 px/s here), and a steady motion under that noise is still
// followed at about its rate.
TEST(BoxTracker, BurstsOfPicturesDoNotThrowThePredictionAway) {
  BoxTracker t;
  t.init({100, 100, 50, 40}, 0);
  t.correct({100, 106, 50, 40}, 1 * kMs);  // 6 px of noise, 1 ms later: no rate yet
  EXPECT_EQ(*t.predict(60 * kMs), cv::Rect2d(100, 106, 50, 40));
  // Then 30 px/s to the right, at irregular stamps, with +-3 px of vertical noise.
  const std::array<std::pair<int, double>, 6> obs{{{40, 3}, {41, -3}, {90, 3}, {140, -3}, {141, 3}, {200, -3}}};
  for (const auto& [t_ms, noise] : obs) t.correct({100 + 0.03 * t_ms, 100 + noise, 50, 40}, t_ms * kMs);
  const cv::Rect2d p = *t.predict(250 * kMs);
  EXPECT_NEAR(p.x, 100 + 0.03 * 250, 2.0);
  EXPECT_NEAR(p.y, 100, 5.0);
}

}  // namespace
}  // namespace shelfcross::flight_sw
