#pragma once
// The colour tags (paper section 3 item 2, docs/method.md section 2): the tag detector, the
// front-shelf test of eq. 1 and the image scale at the front tags.
//
// Image coordinates are OpenCV's: x right, y down, pixels, pixel centres at integer
// coordinates (the convention of cv::projectPoints and of blob moments).

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"

namespace shelfcross::flight_sw {

/// One colour-tag blob.
struct TagBlob {
  cv::Point2d centre_px;  ///< centroid of the blob
  double area_px = 0.0;   ///< pixel count
  cv::Rect bbox_px;
};

/// Paper section 3 item 2: keep the tag colour (HSV range, hue may wrap through red), split
/// the mask into 8-connected blobs, reject blobs by area and shape (fill ratio, aspect).
/// Keeps its buffers between calls so that a steady stream of frames allocates nothing.
///
/// Two implementations, chosen by params.pipeline, giving the same blobs:
///  - reference: cv::cvtColor to HSV, cv::inRange, cv::connectedComponentsWithStats over the
///    whole window.
///  - fast: no HSV image and no full mask. The window is sampled every `stride` pixels
///    (rows and columns) with the exact colour test; each sample that passes seeds an
///    8-connected flood fill at full resolution with the same test, so a blob found is
///    measured exactly as connected components would (same pixels: same area, bounding box and
///    centroid, the latter from integer coordinate sums as OpenCV computes it). The colour
///    test is OpenCV's 8-bit BGR->HSV arithmetic (its division tables, rounding, hue sectors)
///    fused with the range test, bit-exact with cvtColor + inRange (checked on all 2^24
///    colours by the tests). A blob is missed only if no sample falls on it: never for a
///    solid tag of stride + 1 pixels a side or more.
///    Blobs come out in the order connected components numbers them (raster order of the
///    first 2 x 2 block, OpenCV's block-based 8-connected labelling).
class TagDetector {
 public:
  explicit TagDetector(const PerceptionParams& params);
  /// Appends to `out` the tags found inside `roi` of `bgr` (clipped to the image), in image
  /// coordinates. `stride` (fast pipeline only; 0: params.tag_seed_stride_px) is the seed
  /// sampling step. `bgr` must be CV_8UC3 (asserted).
  void detect(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride = 0);
  /// The fused colour test of one BGR pixel (fast pipeline's; exposed for tests).
  bool is_tag_colour(const std::uint8_t* bgr) const;

 private:
  void detect_reference(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out);
  void detect_fast(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride);

  PerceptionParams params_;
  cv::Mat hsv_, mask_, mask_wrap_, labels_, stats_, centroids_;
  // Fast pipeline: per-pixel state of the window (0 unseen, 1 not tag, 2 tag), the fill
  // stack, blobs with their label-order keys, and OpenCV's HSV division tables.
  cv::Mat1b seen_;
  std::vector<cv::Point> stack_;
  std::vector<std::pair<std::int64_t, TagBlob>> found_;
  std::array<int, 256> sdiv_{}, hdiv_{};
};

/// Eq. 1: R_A = S_T / L_T with S_T a tag's area and L_T the largest tag area in `blobs`; tags
/// with R_A < threshold belong to shelves behind the front one and are removed (order kept).
/// Returns L_T (0 when empty).
double keep_front_shelf(std::vector<TagBlob>& blobs, double threshold);

/// Image scale at the front tags, px per metre. With two tags or more: the median distance
/// from each tag to its nearest neighbour over the smallest pitch of the shelf (the nearest
/// neighbour in a grid is one smallest pitch away whatever the rotation, and spacing is
/// measured far more precisely than blob area). With one tag: sqrt(area) / tag side.
double tag_scale_px_per_m(const std::vector<TagBlob>& blobs, const KnownShelf& shelf);

}  // namespace shelfcross::flight_sw
