// The camera against its ground truth: tag blobs where the projector puts them, every visible
// marker decodable, the same bytes for the same pose from one renderer or two.
#include <set>

#include <gtest/gtest.h>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "render/ground_truth.hpp"
#include "render/renderer.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

using test::camera_looking_forward;
using test::paper_test_shelf;

// Tag blobs of the rendered frame and their centroids. Blobs are the connected components of
// the tag colour in HSV; each centroid weighs the pixels of its (dilated) component by their
// coverage, estimated linearly from the green excess G - max(R, B) between the background
// (0) and the blob's full-coverage value, so edge pixels count by the fraction of the tag they
// hold instead of all-or-nothing (a binary mask alone quantises the centroid by up to ~0.5 px).
std::vector<cv::Point2d> tag_blob_centroids(const cv::Mat& bgr) {
  cv::Mat hsv, mask, labels, stats, centroids;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(45, 80, 30), cv::Scalar(85, 255, 255), mask);
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<cv::Point2d> out;
  for (int i = 1; i < n; ++i) {
    if (stats.at<int>(i, cv::CC_STAT_AREA) < 30) continue;
    const cv::Rect box = cv::Rect(stats.at<int>(i, cv::CC_STAT_LEFT) - 2, stats.at<int>(i, cv::CC_STAT_TOP) - 2,
                                  stats.at<int>(i, cv::CC_STAT_WIDTH) + 4, stats.at<int>(i, cv::CC_STAT_HEIGHT) + 4) &
                          cv::Rect(0, 0, bgr.cols, bgr.rows);
    cv::Mat own = labels(box) == i, region;
    cv::dilate(own, region, cv::Mat::ones(3, 3, CV_8U));
    double full = 0.0;
    for (int v = 0; v < box.height; ++v) {
      for (int u = 0; u < box.width; ++u) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(box.y + v, box.x + u);
        if (own.at<uchar>(v, u)) full = std::max(full, static_cast<double>(p[1]) - std::max(p[0], p[2]));
      }
    }
    double w_sum = 0.0, u_sum = 0.0, v_sum = 0.0;
    for (int v = 0; v < box.height; ++v) {
      for (int u = 0; u < box.width; ++u) {
        if (!region.at<uchar>(v, u)) continue;
        const cv::Vec3b p = bgr.at<cv::Vec3b>(box.y + v, box.x + u);
        const double w = std::clamp((static_cast<double>(p[1]) - std::max(p[0], p[2])) / full, 0.0, 1.0);
        w_sum += w;
        u_sum += w * (box.x + u);
        v_sum += w * (box.y + v);
      }
    }
    out.emplace_back(u_sum / w_sum, v_sum / w_sum);
  }
  return out;
}

class RendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { renderer_ = new Renderer(paper_test_shelf(), CameraIntrinsics{}); }
  static void TearDownTestSuite() {
    delete renderer_;
    renderer_ = nullptr;
  }
  static Renderer* renderer_;
};
Renderer* RendererTest::renderer_ = nullptr;

TEST_F(RendererTest, TagBlobCentroidsLieWithinHalfAPixelOfTheGroundTruth) {
  // 1.9 m in front of the shelf face at the height of its middle, slightly turned: every front
  // tag in view. A blob's centroid estimates the centroid of the tag's image region (under
  // perspective and distortion not the projected centre), which the projector computes.
  const Eigen::Isometry3d X_WC = camera_looking_forward({1.1, 0.05, 0.98}, 0.03, 0.02);
  const cv::Mat img = renderer_->render(X_WC);
  ASSERT_EQ(img.size(), cv::Size(960, 720));
  ASSERT_EQ(img.type(), CV_8UC3);
  const GroundTruthProjector truth(paper_test_shelf(), CameraIntrinsics{});
  const std::vector<cv::Point2d> blobs = tag_blob_centroids(img);
  const std::vector<TagProjection> tags = truth.tags(X_WC);
  // Through the open cells the camera also sees the back face's tags, a little offset; where a
  // back tag's image touches its front twin they form one blob, whose centroid is not the
  // front tag's. Those front tags are skipped: the test compares isolated blobs only.
  const auto bbox = [](const TagProjection& t) {
    std::vector<cv::Point2f> c;
    for (const auto& p : t.corners) c.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    return cv::boundingRect(c);
  };
  const auto isolated = [&](const TagProjection& front) {
    const cv::Rect grown = bbox(front) + cv::Size(6, 6) - cv::Point(3, 3);
    for (const TagProjection& back : tags) {
      if (back.front_face || !back.in_front) continue;
      if ((grown & bbox(back)).area() > 0) return false;
    }
    return true;
  };
  int checked = 0;
  double worst = 0.0;
  for (const TagProjection& t : tags) {
    if (!t.visible || !t.front_face || !isolated(t)) continue;
    double best = 1e9;
    for (const cv::Point2d& b : blobs) best = std::min(best, cv::norm(b - t.area_centroid));
    EXPECT_LT(best, 0.5) << "tag at column boundary " << t.column_boundary << ", level boundary " << t.level_boundary
                         << " at pixel " << t.area_centroid << ", area " << t.area_px2;
    worst = std::max(worst, best);
    ++checked;
  }
  EXPECT_GE(checked, 6);
  RecordProperty("worst_centroid_error_px", std::to_string(worst));
}

TEST_F(RendererTest, EveryVisibleMarkerDecodesWhereTheProjectorPutsIt) {
  // 2.1 m from the face: the whole shelf in view, markers about 40 px wide.
  const Eigen::Isometry3d X_WC = camera_looking_forward({0.9, -0.05, 1.0}, -0.02, 0.0);
  const cv::Mat img = renderer_->render(X_WC);
  const GroundTruthProjector truth(paper_test_shelf(), CameraIntrinsics{});
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;  // for the corner comparison
  cv::aruco::detectMarkers(img, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), corners, ids, params);
  std::set<int> visible;
  for (const MarkerProjection& m : truth.markers(X_WC)) {
    if (!m.visible) continue;
    visible.insert(m.marker_id);
    const auto it = std::find(ids.begin(), ids.end(), m.marker_id);
    ASSERT_NE(it, ids.end()) << "marker " << m.marker_id << " not decoded";
    const auto& c = corners[static_cast<size_t>(it - ids.begin())];
    for (int k = 0; k < 4; ++k) {
      EXPECT_LT(cv::norm(cv::Point2d(c[static_cast<size_t>(k)]) - m.corners[static_cast<size_t>(k)]), 1.0)
          << "marker " << m.marker_id << " corner " << k;
    }
  }
  EXPECT_EQ(visible.size(), 5u);
  EXPECT_EQ(std::set<int>(ids.begin(), ids.end()), visible);
}

TEST_F(RendererTest, SamePoseGivesTheSameBytesFromOneRendererOrTwo) {
  const Eigen::Isometry3d X_WC = camera_looking_forward({2.2, 0.1, 1.1}, 0.1, 0.05);
  const cv::Mat a = renderer_->render(X_WC, 7);
  const cv::Mat b = renderer_->render(X_WC, 7);
  RenderOptions noisy;
  Renderer other(paper_test_shelf(), CameraIntrinsics{}, noisy);
  const cv::Mat c = other.render(X_WC, 7);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0);
}

TEST_F(RendererTest, NoiseIsSeededAndRetargetingRestoresTheScene) {
  RenderOptions opts;
  opts.noise_stddev = 3.0;
  Renderer r(paper_test_shelf(), CameraIntrinsics{}, opts);
  const Eigen::Isometry3d X_WC = camera_looking_forward({1.5, 0.0, 1.0});
  const cv::Mat n1 = r.render(X_WC, 1), n1b = r.render(X_WC, 1), n2 = r.render(X_WC, 2);
  EXPECT_EQ(cv::norm(n1, n1b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(n1, n2, cv::NORM_INF), 0.0);
  // Another box placement changes the picture; going back gives the original bytes.
  Warehouse moved = paper_test_shelf();
  moved.shelves[0].boxes = {{2, 2, 9}};
  r.set_warehouse(moved);
  const cv::Mat m = r.render(X_WC, 1);
  EXPECT_GT(cv::norm(n1, m, cv::NORM_INF), 0.0);
  r.set_warehouse(paper_test_shelf());
  EXPECT_EQ(cv::norm(n1, r.render(X_WC, 1), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace shelfcross::render
