#include "flight_sw/perception/tag_detector.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace shelfcross::flight_sw {

TagDetector::TagDetector(const PerceptionParams& params) : params_(params) {
  // OpenCV's 8-bit BGR->HSV tables (color_hsv: hsv_shift = 12, H range 180):
  // sdiv[v] = round(255 * 2^12 / v), hdiv[d] = round(180 * 2^12 / (6 d)).
  for (int i = 1; i < 256; ++i) {
    sdiv_[static_cast<size_t>(i)] = cvRound((255 << 12) / (1.0 * i));
    hdiv_[static_cast<size_t>(i)] = cvRound((180 << 12) / (6.0 * i));
  }
}

void TagDetector::detect(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride) {
  assert(bgr.type() == CV_8UC3);
  roi &= cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (roi.empty()) return;
  const size_t first = out.size();
  if (params_.pipeline == PerceptionPipeline::reference) {
    detect_reference(bgr, roi, out);
  } else {
    detect_fast(bgr, roi, out, stride > 0 ? stride : params_.tag_seed_stride_px);
  }
  // A tag is a solid square: its centroid pixel has the tag colour. A box face whose colour
  // the hue window reaches (cardboard, hue about 15, under a yellow tag's window 12..48) is a
  // ring around its marker's white sheet, so its centroid is not; dropped here, it can
  // neither pass as a tag nor, as the largest blob, push the real tags out through eq. 1.
  const auto solid = [&](const TagBlob& b) {
    const int x = std::clamp(static_cast<int>(std::lround(b.centre_px.x)), 0, bgr.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(b.centre_px.y)), 0, bgr.rows - 1);
    return is_tag_colour(bgr.ptr<std::uint8_t>(y) + 3 * x);
  };
  out.erase(std::stable_partition(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(), solid), out.end());
}

void TagDetector::detect_reference(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out) {
  cv::cvtColor(bgr(roi), hsv_, cv::COLOR_BGR2HSV);
  const HsvRange& r = params_.tag_hsv;
  if (r.hue_min <= r.hue_max) {
    cv::inRange(hsv_, cv::Scalar(r.hue_min, r.sat_min, r.val_min),
                cv::Scalar(r.hue_max, r.sat_max, r.val_max), mask_);
  } else {  // the range wraps through red: [hue_min, 179] or [0, hue_max]
    cv::inRange(hsv_, cv::Scalar(r.hue_min, r.sat_min, r.val_min),
                cv::Scalar(179, r.sat_max, r.val_max), mask_);
    cv::inRange(hsv_, cv::Scalar(0, r.sat_min, r.val_min),
                cv::Scalar(r.hue_max, r.sat_max, r.val_max), mask_wrap_);
    cv::bitwise_or(mask_, mask_wrap_, mask_);
  }
  const int n = cv::connectedComponentsWithStats(mask_, labels_, stats_, centroids_, 8, CV_32S);
  for (int i = 1; i < n; ++i) {  // label 0 is the background
    const int* s = stats_.ptr<int>(i);
    const double area = s[cv::CC_STAT_AREA];
    const int w = s[cv::CC_STAT_WIDTH], h = s[cv::CC_STAT_HEIGHT];
    if (area < params_.min_tag_area_px) continue;
    if (area < params_.min_fill_ratio * w * h) continue;  // ragged or hollow: not a tag
    if (std::max(w, h) > params_.max_aspect_ratio * std::min(w, h)) continue;  // a bar edge
    const double* c = centroids_.ptr<double>(i);
    out.push_back({cv::Point2d(c[0] + roi.x, c[1] + roi.y), area,
                   cv::Rect(s[cv::CC_STAT_LEFT] + roi.x, s[cv::CC_STAT_TOP] + roi.y, w, h)});
  }
}

// OpenCV's RGB2HSV_b for one pixel, then inRange: V = max; S = round(255 (V - min) / V) by
// the table; H by sector (V == R first, then V == G), scaled by the table, + 180 if negative.
bool TagDetector::is_tag_colour(const std::uint8_t* p) const {
  const int b = p[0], g = p[1], r = p[2];
  const HsvRange& rg = params_.tag_hsv;
  const int v = std::max(b, std::max(g, r));
  if (v < rg.val_min || v > rg.val_max) return false;
  const int diff = v - std::min(b, std::min(g, r));
  const int s = (diff * sdiv_[static_cast<size_t>(v)] + (1 << 11)) >> 12;
  if (s < rg.sat_min || s > rg.sat_max) return false;
  int h = v == r ? g - b : v == g ? b - r + 2 * diff : r - g + 4 * diff;
  h = (h * hdiv_[static_cast<size_t>(diff)] + (1 << 11)) >> 12;
  if (h < 0) h += 180;
  if (rg.hue_min <= rg.hue_max) return h >= rg.hue_min && h <= rg.hue_max;
  return (h >= rg.hue_min && h <= 179) || h <= rg.hue_max;
}

void TagDetector::detect_fast(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride) {
  assert(stride >= 1);
  if (seen_.rows < bgr.rows || seen_.cols < bgr.cols) seen_.create(bgr.rows, bgr.cols);  // once
  cv::Mat1b seen = seen_(roi);
  seen.setTo(0);
  found_.clear();
  const int W = roi.width, H = roi.height;
  const auto pixel = [&](int x, int y) { return bgr.ptr<std::uint8_t>(roi.y + y) + 3 * (roi.x + x); };
  for (int y0 = 0; y0 < H; y0 += stride) {
    std::uint8_t* seen_row = seen.ptr<std::uint8_t>(y0);
    for (int x0 = 0; x0 < W; x0 += stride) {
      // A sample already filled is skipped; one that fails is not marked (nothing returns to it).
      if (seen_row[x0] == 2 || !is_tag_colour(pixel(x0, y0))) continue;
      // 8-connected flood fill of the blob at full resolution (window coordinates).
      seen_row[x0] = 2;
      stack_.clear();
      stack_.emplace_back(x0, y0);
      std::int64_t sum_x = 0, sum_y = 0;
      int area = 0, left = x0, right = x0, top = y0, bottom = y0;
      int first_block_row = y0 >> 1, first_block_col = x0 >> 1;
      while (!stack_.empty()) {
        const cv::Point q = stack_.back();
        stack_.pop_back();
        ++area;
        sum_x += q.x;
        sum_y += q.y;
        left = std::min(left, q.x);
        right = std::max(right, q.x);
        top = std::min(top, q.y);
        bottom = std::max(bottom, q.y);
        const int br = q.y >> 1, bc = q.x >> 1;
        if (br < first_block_row || (br == first_block_row && bc < first_block_col)) {
          first_block_row = br;
          first_block_col = bc;
        }
        for (int ny = std::max(0, q.y - 1); ny <= std::min(H - 1, q.y + 1); ++ny) {
          std::uint8_t* row = seen.ptr<std::uint8_t>(ny);
          for (int nx = std::max(0, q.x - 1); nx <= std::min(W - 1, q.x + 1); ++nx) {
            if (row[nx]) continue;
            if (is_tag_colour(pixel(nx, ny))) {
              row[nx] = 2;
              stack_.emplace_back(nx, ny);
            } else {
              row[nx] = 1;
            }
          }
        }
      }
      const int w = right - left + 1, h = bottom - top + 1;
      if (area < params_.min_tag_area_px) continue;
      if (area < params_.min_fill_ratio * w * h) continue;
      if (std::max(w, h) > params_.max_aspect_ratio * std::min(w, h)) continue;
      const double a = area;
      const std::int64_t key = (static_cast<std::int64_t>(first_block_row) << 32) | first_block_col;
      found_.push_back({key, TagBlob{cv::Point2d(static_cast<double>(sum_x) / a + roi.x,
                                                 static_cast<double>(sum_y) / a + roi.y),
                                     a, cv::Rect(left + roi.x, top + roi.y, w, h)}});
    }
  }
  std::sort(found_.begin(), found_.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  for (const auto& f : found_) out.push_back(f.second);
}

double keep_front_shelf(std::vector<TagBlob>& blobs, double threshold) {
  double largest = 0.0;
  for (const TagBlob& b : blobs) largest = std::max(largest, b.area_px);
  std::erase_if(blobs, [&](const TagBlob& b) { return b.area_px < threshold * largest; });
  return largest;
}

double tag_scale_px_per_m(const std::vector<TagBlob>& blobs, const KnownShelf& shelf) {
  if (blobs.empty()) return 0.0;
  if (blobs.size() == 1) return std::sqrt(blobs[0].area_px) / shelf.tag_size_m;
  std::vector<double> nearest(blobs.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < blobs.size(); ++i) {
    for (size_t j = i + 1; j < blobs.size(); ++j) {
      const double d = cv::norm(blobs[i].centre_px - blobs[j].centre_px);
      nearest[i] = std::min(nearest[i], d);
      nearest[j] = std::min(nearest[j], d);
    }
  }
  auto mid = nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2);
  std::nth_element(nearest.begin(), mid, nearest.end());
  const double min_pitch = std::min(
      *std::min_element(shelf.column_pitch_m.begin(), shelf.column_pitch_m.end()),
      *std::min_element(shelf.row_pitch_m.begin(), shelf.row_pitch_m.end()));
  return *mid / min_pitch;
}

}  // namespace shelfcross::flight_sw
