#include "flight_sw/perception.hpp"
#include "shelfcross/aruco_dictionaries.hpp"

#include <algorithm>
#include <functional>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>

#include <opencv2/imgproc.hpp>

namespace shelfcross::flight_sw {

std::optional<int> aruco_dictionary_id(const std::string& name) {
  const ArucoDictionaryEntry* e = find_aruco_dictionary(name);
  if (!e) return std::nullopt;
  return e->id;
}

// ---- Tags ----

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

// ---- Grid: eq. 2, 3, 4 ----

GridLimits grid_limits(double w, double h) {
  assert(w > 0.0 && h > 0.0);
  const double diag = std::hypot(w, h);
  const double lo = std::min(w, h);
  GridLimits l;
  if (w >= h) {
    l.dx_lim_px = lo * lo / diag;
    l.dy_lim_px = w * h / diag;
  } else {
    l.dx_lim_px = w * h / diag;
    l.dy_lim_px = lo * lo / diag;
  }
  l.theta_lim_rad = std::atan(lo / std::max(w, h));
  return l;
}

GridLimits grid_limits(const KnownShelf& shelf, double px_per_m) {
  const auto [w_min, w_max] = std::minmax_element(shelf.column_pitch_m.begin(), shelf.column_pitch_m.end());
  const auto [h_min, h_max] = std::minmax_element(shelf.row_pitch_m.begin(), shelf.row_pitch_m.end());
  // Eq. 3-4 generalised. A row's chain must take its co-row neighbour, up to W
  // away (the widest column), at |dy| = W sin(theta), and never a point of the next row, whose
  // offset h cos(theta) - w sin(theta) (the diagonal neighbour) vanishes first for the lowest
  // row h_min over the widest column: theta < atan(h_min / W). Columns alike:
  // theta < atan(w_min / H). So theta_L = min(atan(h_min / W), atan(w_min / H)) and the windows
  // are the co-line offsets at theta_L: dy_lim = W sin(theta_L), dx_lim = H sin(theta_L).
  // For a uniform grid this is eq. 3-4 exactly (w >= h: theta_L = atan(h / w),
  // dy_lim = w h / sqrt(w^2 + h^2), dx_lim = h^2 / sqrt(w^2 + h^2)); eq. 3 with the largest
  // pitches alone gave rows of 0.30 m under columns of 0.52 m (W H / sqrt(W^2 + H^2) = 0.33 m
  // with H = 0.42 m) a row window wider than a row: theta_L = 0, every view refused.
  GridLimits l;
  l.theta_lim_rad = std::min(std::atan(*h_min / *w_max), std::atan(*w_min / *h_max));
  l.dy_lim_px = *w_max * px_per_m * std::sin(l.theta_lim_rad);
  l.dx_lim_px = *h_max * px_per_m * std::sin(l.theta_lim_rad);
  return l;
}

namespace {

// Eq. 2 along one axis: chains of points, each the nearest along `a` (strictly ahead) within
// |b_Q - b_P| <= lim of the previous one. Starts from the unassigned point with the smallest
// `a` (the corner end of its line). a = x, b = y for rows; a = y, b = x for columns.
template <class A, class B>
std::vector<std::vector<int>> stair_chains(const std::vector<cv::Point2d>& p, A a, B b, double lim) {
  const size_t n = p.size();
  std::vector<int> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return a(p[i]) < a(p[j]); });
  std::vector<char> used(n, 0);
  std::vector<std::vector<int>> chains;
  for (int start : order) {
    if (used[start]) continue;
    std::vector<int> chain{start};
    used[start] = 1;
    int cur = start;
    for (;;) {
      int best = -1;
      double best_da = std::numeric_limits<double>::infinity();
      for (int q : order) {
        if (used[q]) continue;
        const double da = a(p[q]) - a(p[cur]);
        if (da <= 0.0 || std::abs(b(p[q]) - b(p[cur])) > lim) continue;
        if (da < best_da) {
          best_da = da;
          best = q;
        }
      }
      if (best < 0) break;
      chain.push_back(best);
      used[best] = 1;
      cur = best;
    }
    chains.push_back(std::move(chain));
  }
  return chains;
}

}  // namespace

TagGrid classify_grid(const std::vector<cv::Point2d>& pts, const GridLimits& lim,
                      double orthogonality_tolerance_rad) {
  TagGrid g;
  const size_t n = pts.size();
  g.row.assign(n, -1);
  g.column.assign(n, -1);
  if (n == 0) {
    g.refusal = "no tags";
    return g;
  }
  auto px = [](const cv::Point2d& q) { return q.x; };
  auto py = [](const cv::Point2d& q) { return q.y; };
  const auto rows = stair_chains(pts, px, py, lim.dy_lim_px);
  const auto cols = stair_chains(pts, py, px, lim.dx_lim_px);

  // Rotation from the summed chain steps: rows run along u = (cos t, sin t), columns (top to
  // bottom) along v = (-sin t, cos t).
  cv::Point2d row_sum(0, 0), col_sum(0, 0);
  int row_steps = 0, col_steps = 0;
  for (const auto& c : rows) {
    for (size_t k = 1; k < c.size(); ++k, ++row_steps) row_sum += pts[c[k]] - pts[c[k - 1]];
  }
  for (const auto& c : cols) {
    for (size_t k = 1; k < c.size(); ++k, ++col_steps) col_sum += pts[c[k]] - pts[c[k - 1]];
  }
  const double theta_r = row_steps ? std::atan2(row_sum.y, row_sum.x) : 0.0;
  const double theta_c = col_steps ? std::atan2(-col_sum.x, col_sum.y) : 0.0;
  auto deg = [](double r) { return std::to_string(r * 180.0 / M_PI); };
  if (std::abs(theta_r) >= lim.theta_lim_rad || std::abs(theta_c) >= lim.theta_lim_rad) {
    g.refusal = "grid rotated past the limit angle (rows " + deg(theta_r) + " deg, columns " +
                deg(theta_c) + " deg, limit " + deg(lim.theta_lim_rad) + " deg)";
    return g;
  }
  if (row_steps && col_steps && std::abs(theta_r - theta_c) > orthogonality_tolerance_rad) {
    g.refusal = "row and column directions disagree (" + deg(theta_r) + " vs " + deg(theta_c) +
                " deg): rotation near or past the limit";
    return g;
  }
  const double t = row_steps && col_steps ? 0.5 * (theta_r + theta_c) : (row_steps ? theta_r : theta_c);
  g.rotation_rad = t;
  const cv::Point2d u(std::cos(t), std::sin(t)), v(-std::sin(t), std::cos(t));

  // Order the lines: rows by their mean along v (largest = lowest in the image = row 0),
  // columns by their mean along u (smallest = leftmost = column 0).
  auto order_lines = [&](const std::vector<std::vector<int>>& lines, const cv::Point2d& axis,
                         bool descending, std::vector<int>& label) {
    std::vector<std::pair<double, size_t>> key;
    for (size_t i = 0; i < lines.size(); ++i) {
      double s = 0.0;
      for (int k : lines[i]) s += pts[k].dot(axis);
      s /= static_cast<double>(lines[i].size());
      key.emplace_back(descending ? -s : s, i);
    }
    std::sort(key.begin(), key.end());
    for (size_t rank = 0; rank < key.size(); ++rank) {
      for (int k : lines[key[rank].second]) label[k] = static_cast<int>(rank);
    }
  };
  order_lines(rows, v, true, g.row);
  order_lines(cols, u, false, g.column);
  g.rows = static_cast<int>(rows.size());
  g.columns = static_cast<int>(cols.size());

  // Consistency: one point per (row, column); columns increase along each row chain and rows
  // decrease (upward is +row) along each column chain (top to bottom).
  g.index.assign(static_cast<size_t>(g.rows * g.columns), -1);
  for (size_t k = 0; k < n; ++k) {
    int& slot = g.index[static_cast<size_t>(g.row[k] * g.columns + g.column[k])];
    if (slot >= 0) {
      g.refusal = "two tags on one grid position: classification inconsistent";
      return g;
    }
    slot = static_cast<int>(k);
  }
  for (const auto& c : rows) {
    for (size_t k = 1; k < c.size(); ++k) {
      if (g.column[c[k]] <= g.column[c[k - 1]]) {
        g.refusal = "row chain crosses columns backwards: classification inconsistent";
        return g;
      }
    }
  }
  for (const auto& c : cols) {
    for (size_t k = 1; k < c.size(); ++k) {
      if (g.row[c[k]] >= g.row[c[k - 1]]) {
        g.refusal = "column chain crosses rows backwards: classification inconsistent";
        return g;
      }
    }
  }
  g.valid = true;
  return g;
}

std::optional<std::array<int, 4>> cell_corner_indices(const TagGrid& grid, int r, int c) {
  if (!grid.valid || r < 0 || c < 0 || r + 1 >= grid.rows || c + 1 >= grid.columns) {
    return std::nullopt;
  }
  const std::array<int, 4> idx{grid.at(r, c), grid.at(r, c + 1), grid.at(r + 1, c + 1),
                               grid.at(r + 1, c)};
  for (int i : idx) {
    if (i < 0) return std::nullopt;
  }
  return idx;
}

// ---- Markers ----

MarkerDetector::MarkerDetector(const std::string& dictionary_name) {
  const auto id = aruco_dictionary_id(dictionary_name);
  if (!id) throw std::invalid_argument("unknown ArUco dictionary '" + dictionary_name + "'");
  dictionary_ = cv::aruco::getPredefinedDictionary(*id);
  parameters_ = cv::aruco::DetectorParameters::create();
  parameters_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  fast_parameters_ = cv::aruco::DetectorParameters::create();
  fast_parameters_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
}

void MarkerDetector::collect(double scale, cv::Point2d offset, double grow_px, std::vector<MarkerSighting>& out) {
  // Pixel u of an image decimated by `scale` (block average) covers full-resolution pixels
  // scale u .. scale u + scale - 1: its centre is scale u + (scale - 1) / 2.
  const double shift = 0.5 * (scale - 1.0);
  for (size_t i = 0; i < ids_.size(); ++i) {
    MarkerSighting m;
    m.id = ids_[i];
    std::array<cv::Point2d, 4> q;
    cv::Point2d c(0, 0);
    for (size_t k = 0; k < 4; ++k) {
      q[k] = cv::Point2d(scale * corners_[i][k].x + shift + offset.x, scale * corners_[i][k].y + shift + offset.y);
      c += 0.25 * q[k];
    }
    // Unrefined corners lie on the centres of the border's outermost dark pixels, half a pixel
    // inside its edge: every side moved out by grow_px (miter: corner + d (n1 + n2) / (1 + n1.n2)
    // with n1, n2 the outward unit normals of its two sides).
    c = cv::Point2d(0, 0);
    for (size_t k = 0; k < 4; ++k) {
      cv::Point2d p = q[k];
      if (grow_px > 0.0) {
        const auto outward = [&](const cv::Point2d& a, const cv::Point2d& b) {
          const cv::Point2d e = b - a;
          cv::Point2d n(-e.y, e.x);
          n *= 1.0 / std::max(1e-9, cv::norm(n));
          const cv::Point2d centre = 0.25 * (q[0] + q[1] + q[2] + q[3]);
          return n.dot(0.5 * (a + b) - centre) >= 0.0 ? n : -n;
        };
        const cv::Point2d n1 = outward(q[(k + 3) % 4], q[k]), n2 = outward(q[k], q[(k + 1) % 4]);
        p += grow_px * (n1 + n2) * (1.0 / std::max(0.1, 1.0 + n1.dot(n2)));
      }
      m.corners_px[k] = cv::Point2f(p);
      c += cv::Point2d(m.corners_px[k]);
    }
    m.centre_px = c * 0.25;
    m.area_px = std::abs(cv::contourArea(m.corners_px));
    out.push_back(m);
  }
}

void MarkerDetector::detect(const cv::Mat& bgr, std::vector<MarkerSighting>& out) {
  cv::cvtColor(bgr, gray_, cv::COLOR_BGR2GRAY);
  corners_.clear();
  ids_.clear();
  cv::aruco::detectMarkers(gray_, dictionary_, corners_, ids_, parameters_, rejected_);
  collect(1.0, {0.0, 0.0}, 0.0, out);  // sub-pixel refined
}

void MarkerDetector::detect_in(const cv::Mat& bgr, cv::Rect region, double expected_side_px,
                               double min_area_ratio, std::vector<MarkerSighting>& out) {
  region &= cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (region.width < 8 || region.height < 8 || !(expected_side_px > 0.0)) return;
  cv::cvtColor(bgr(region), gray_, cv::COLOR_BGR2GRAY);
  const double side = expected_side_px;
  const double longest = std::max(gray_.cols, gray_.rows);
  cv::aruco::DetectorParameters& p = *fast_parameters_;
  // A quadrilateral of perimeter P has at most the area (P/4)^2 (the square's), so one with
  // P < 4 sqrt(marker_area_ratio) side can never pass eq. 1 on marker area (area >= ratio
  // side^2): such candidates (the colour tags, markers of shelves behind) are not even decoded.
  p.minMarkerPerimeterRate = std::min(4.0, 0.98 * std::sqrt(min_area_ratio) * 4.0 * side / longest);
  p.maxMarkerPerimeterRate = std::min(4.0, 2.5 * 4.0 * side / longest);
  // One threshold window about half a marker wide (the defaults try 3, 13 and 23 px): a
  // marker's black border and white bits both fall inside it.
  const int window = std::clamp(2 * static_cast<int>(std::lround(0.25 * side)) + 1, 5, 31);
  p.adaptiveThreshWinSizeMin = window;
  p.adaptiveThreshWinSizeMax = window;
  p.adaptiveThreshWinSizeStep = 10;
  corners_.clear();
  ids_.clear();
  cv::aruco::detectMarkers(gray_, dictionary_, corners_, ids_, fast_parameters_, rejected_);
  collect(1.0, cv::Point2d(region.x, region.y), 0.5, out);
}

// ---- Tracking ----

void BoxTracker::init(const cv::Rect2d& box, TimeNs t_ns) {
  recent_.assign(1, {t_ns, {box.x + 0.5 * box.width, box.y + 0.5 * box.height, box.width, box.height}});
  rate_per_s_ = {0, 0, 0, 0};
}

void BoxTracker::correct(const cv::Rect2d& box, TimeNs t_ns) {
  const double dt = recent_.empty() ? 0.0 : ns_to_seconds(t_ns - recent_.back().t_ns);
  if (recent_.empty() || dt < 0.0 || dt > kCoast_s) {
    init(box, t_ns);
    return;
  }
  recent_.push_back({t_ns, {box.x + 0.5 * box.width, box.y + 0.5 * box.height, box.width, box.height}});
  while (ns_to_seconds(t_ns - recent_.front().t_ns) > kRateWindow_s) recent_.pop_front();
  // Least-squares slope of each component over the window: sum (t - t_mean)(v - v_mean) /
  // sum (t - t_mean)^2, times relative to the newest (seconds, well conditioned).
  rate_per_s_ = {0, 0, 0, 0};
  if (ns_to_seconds(t_ns - recent_.front().t_ns) < kRateMinSpan_s) return;
  const double n = static_cast<double>(recent_.size());
  double t_mean = 0.0;
  cv::Vec4d v_mean(0, 0, 0, 0);
  for (const Measured& m : recent_) {
    t_mean += ns_to_seconds(m.t_ns - t_ns) / n;
    v_mean += m.v * (1.0 / n);
  }
  double stt = 0.0;
  cv::Vec4d stv(0, 0, 0, 0);
  for (const Measured& m : recent_) {
    const double dt_s = ns_to_seconds(m.t_ns - t_ns) - t_mean;
    stt += dt_s * dt_s;
    stv += (m.v - v_mean) * dt_s;
  }
  rate_per_s_ = stv * (1.0 / stt);
}

std::optional<cv::Rect2d> BoxTracker::predict(TimeNs t_ns) const {
  if (recent_.empty()) return std::nullopt;
  const cv::Vec4d& last = recent_.back().v;
  const cv::Rect2d last_box(last[0] - 0.5 * last[2], last[1] - 0.5 * last[3], last[2], last[3]);
  const double dt = ns_to_seconds(t_ns - recent_.back().t_ns);
  if (dt <= 0.0 || dt > kCoast_s) return last_box;
  const double w = std::max(1.0, last[2] + rate_per_s_[2] * dt);
  const double h = std::max(1.0, last[3] + rate_per_s_[3] * dt);
  const double cx = last[0] + rate_per_s_[0] * dt;
  const double cy = last[1] + rate_per_s_[1] * dt;
  return cv::Rect2d(cx - 0.5 * w, cy - 0.5 * h, w, h);
}

bool rows_touch(const std::vector<RowSpan>& rows, double top_px, double bottom_px) {
  return std::any_of(rows.begin(), rows.end(),
                     [&](const RowSpan& r) { return r.v_begin_px < bottom_px && r.v_end_px > top_px; });
}

// ---- The front shelf in one frame ----

void analyse_shelf(const cv::Mat& bgr, TagDetector& detector, const FlightConfig& config,
                   ShelfView& view) {
  view.tags.clear();
  view.full = false;
  view.grid = TagGrid{};
  detector.detect(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows), view.tags);
  view.largest_tag_area_px = keep_front_shelf(view.tags, config.perception.area_ratio_threshold);
  view.px_per_m = tag_scale_px_per_m(view.tags, config.shelf);
  if (view.tags.empty()) {
    view.grid.refusal = "no tags";
    return;
  }
  std::vector<cv::Point2d> pts;
  pts.reserve(view.tags.size());
  for (const TagBlob& b : view.tags) pts.push_back(b.centre_px);
  view.grid = classify_grid(pts, grid_limits(config.shelf, view.px_per_m),
                            config.perception.grid_orthogonality_tolerance_rad);
  const int expect_rows = config.shelf.levels() + 1, expect_cols = config.shelf.columns() + 1;
  const size_t expect = static_cast<size_t>(expect_rows * expect_cols);
  // A shelf behind, seen from afar: eq. 1 keeps its tags when r / (r + d) > sqrt(0.45) (from
  // 3.5 m, a shelf up to 1.7 m behind), and the grid then holds more tags than the known
  // shelf has. The front shelf's tags are the nearer ones: with the vehicle turned by up to
  // psi, they lie within r +- (W/2) sin(psi) and those of a shelf d behind beyond
  // r + d - (W/2) sin(psi), so for d > W sin(psi) (1.2 m > 1.7 m x sin 20 deg = 0.58 m) the
  // known number of largest tags are the front shelf's. They are kept only if they then
  // classify as the whole known grid; otherwise the view stays as it was (not full).
  if (!(view.grid.valid && view.grid.rows == expect_rows && view.grid.columns == expect_cols) && view.tags.size() > expect) {
    std::vector<double> areas;
    for (const TagBlob& b : view.tags) areas.push_back(b.area_px);
    std::nth_element(areas.begin(), areas.begin() + static_cast<std::ptrdiff_t>(expect - 1), areas.end(), std::greater<>());
    const double smallest_kept = areas[expect - 1];
    std::vector<TagBlob> front;
    for (const TagBlob& b : view.tags) {
      if (b.area_px >= smallest_kept) front.push_back(b);
    }
    if (front.size() == expect) {
      std::vector<cv::Point2d> front_pts;
      for (const TagBlob& b : front) front_pts.push_back(b.centre_px);
      const double px_per_m = tag_scale_px_per_m(front, config.shelf);
      TagGrid grid = classify_grid(front_pts, grid_limits(config.shelf, px_per_m),
                                   config.perception.grid_orthogonality_tolerance_rad);
      if (grid.valid && grid.rows == expect_rows && grid.columns == expect_cols) {
        view.tags = std::move(front);
        view.px_per_m = px_per_m;
        view.grid = std::move(grid);
      }
    }
  }
  if (!view.grid.valid) return;
  view.full = view.grid.rows == expect_rows && view.grid.columns == expect_cols &&
              static_cast<int>(view.tags.size()) == expect_rows * expect_cols;
}

std::array<cv::Point2d, 4> cell_quad(const ShelfView& view, CellIndex cell) {
  const auto idx = cell_corner_indices(view.grid, cell.level - 1, cell.column - 1);
  assert(idx);
  std::array<cv::Point2d, 4> q;
  for (size_t k = 0; k < 4; ++k) q[k] = view.tags[static_cast<size_t>((*idx)[k])].centre_px;
  return q;
}

std::vector<std::pair<CellIndex, int>> assign_markers(const ShelfView& view,
                                                      const std::vector<MarkerSighting>& markers,
                                                      const FlightConfig& config) {
  assert(view.full);
  std::vector<std::pair<CellIndex, int>> out;
  const double side = config.shelf.marker_size_m * view.px_per_m;
  const double expected_area = side * side;
  for (const MarkerSighting& m : markers) {
    if (m.area_px < config.perception.marker_area_ratio_threshold * expected_area) continue;
    for (int level = 1; level <= config.shelf.levels(); ++level) {
      for (int column = 1; column <= config.shelf.columns(); ++column) {
        const auto q = cell_quad(view, {level, column});
        const std::vector<cv::Point2f> poly(q.begin(), q.end());
        if (cv::pointPolygonTest(poly, cv::Point2f(m.centre_px), false) > 0) {
          out.push_back({{level, column}, m.id});
        }
      }
    }
  }
  return out;
}

}  // namespace shelfcross::flight_sw
