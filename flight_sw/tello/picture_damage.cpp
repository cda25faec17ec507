#include "flight_sw/tello/picture_damage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace shelfcross::tello {
namespace {

constexpr int kMbPx = 16;
// Rows the luma 6-tap interpolation filter reads beyond a fractional source row (H.264
// 8.4.2.2.1: taps at -2..+3).
constexpr int kFilterAbovePx = 2;
constexpr int kFilterBelowPx = 3;

// floor(a / b) for b > 0.
int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
// Pictures the standard lets a stream keep for reference (max_num_ref_frames <= 16).
constexpr int kMaxRefs = 16;

void mark(std::vector<std::uint8_t>& mask, int v_begin_px, int v_end_px) {
  const int h = static_cast<int>(mask.size());
  std::fill(mask.begin() + std::clamp(v_begin_px, 0, h), mask.begin() + std::clamp(v_end_px, 0, h), std::uint8_t{1});
}

bool any(const std::vector<std::uint8_t>& mask, int v_begin_px, int v_end_px) {
  const int h = static_cast<int>(mask.size());
  const auto b = mask.begin() + std::clamp(v_begin_px, 0, h), e = mask.begin() + std::clamp(v_end_px, 0, h);
  return std::find(b, e, std::uint8_t{1}) != e;
}

// Whether a prediction reading rows first..last (inclusive) of a reference picture reads a
// damaged one: rows beyond the picture's edges read its edge rows (H.264 8.4.2.2: the
// reference is extended by repeating them).
bool reads(const std::vector<std::uint8_t>& mask, int first, int last) {
  const int h = static_cast<int>(mask.size());
  return any(mask, std::clamp(first, 0, h - 1), std::clamp(last, 0, h - 1) + 1);
}

std::vector<RowSpan> spans(const std::vector<std::uint8_t>& mask) {
  std::vector<RowSpan> out;
  const int h = static_cast<int>(mask.size());
  for (int v = 0; v < h;) {
    if (!mask[v]) {
      ++v;
      continue;
    }
    const int begin = v;
    while (v < h && mask[v]) ++v;
    out.push_back({begin, v});
  }
  return out;
}

}  // namespace

namespace {

using Ranges = std::vector<std::pair<int, int>>;

// Adds [first, end) to sorted, disjoint `r`, merging.
void add_range(Ranges& r, int first, int end) {
  if (end <= first) return;
  r.push_back({first, end});
  std::sort(r.begin(), r.end());
  Ranges merged;
  for (const auto& x : r) {
    if (!merged.empty() && x.first <= merged.back().second) merged.back().second = std::max(merged.back().second, x.second);
    else merged.push_back(x);
  }
  r.swap(merged);
}

int count(const Ranges& r) {
  int n = 0;
  for (const auto& [first, end] : r) n += end - first;
  return n;
}

}  // namespace

std::vector<std::pair<int, int>> suspect_macroblocks(const PictureEvidence& e, int macroblocks, int slice_mbs) {
  const std::vector<sdk::SliceSpan>& slices = e.slices;
  for (std::size_t i = 1; i < slices.size(); ++i) {
    if (slices[i].first_mb <= slices[i - 1].first_mb) return {{0, macroblocks}};
  }
  if (slices.empty() || slices.back().first_mb >= macroblocks) return {{0, macroblocks}};
  const bool layout = slice_mbs > 0 && std::all_of(slices.begin(), slices.end(), [&](const sdk::SliceSpan& s) {
                        return s.first_mb % slice_mbs == 0;
                      });
  Ranges gaps, spanning;
  add_range(gaps, 0, slices.front().first_mb);
  for (std::size_t i = 0; i < slices.size(); ++i) {
    const sdk::SliceSpan& s = slices[i];
    const int next = i + 1 < slices.size() ? slices[i + 1].first_mb : macroblocks;
    const bool boundary = std::any_of(e.datagram_ends.begin(), e.datagram_ends.end(),
                                      [&](std::size_t end) { return end > s.begin && end <= s.end; });
    if (layout && next != std::min(s.first_mb + slice_mbs, macroblocks)) {
      // ... and the slice after the gap: libavcodec's error resilience conceals it too where
      // the missing slices' neighbours decide it (found by the check against the truth).
      add_range(gaps, s.first_mb, std::min(next + slice_mbs, macroblocks));
    } else if (boundary) {
      add_range(spanning, s.first_mb, next);
    }
  }
  const auto in_gaps = [&](int mb) {
    return std::any_of(gaps.begin(), gaps.end(), [&](const auto& g) { return mb >= g.first && mb < g.second; });
  };
  const bool vouched = layout && e.concealed_mbs <= count(gaps) && std::all_of(e.error_mbs.begin(), e.error_mbs.end(), in_gaps);
  if (!vouched) {
    for (const auto& [first, end] : spanning) add_range(gaps, first, end);
  }
  return gaps;
}

PictureDamage::PictureDamage(int width_px, int height_px, int concealment_reach_px)
    : width_px_(width_px), height_px_(height_px), mb_cols_((width_px + kMbPx - 1) / kMbPx),
      mb_rows_((height_px + kMbPx - 1) / kMbPx), reach_px_(concealment_reach_px) {
  if (width_px <= 0 || height_px <= 0 || concealment_reach_px < 0) {
    throw std::invalid_argument("PictureDamage: picture " + std::to_string(width_px) + " x " +
                                std::to_string(height_px) + ", reach " + std::to_string(concealment_reach_px));
  }
}

void PictureDamage::learn_layout(const std::vector<sdk::SliceSpan>& slices) {
  // One size for all but the last slice, which may be shorter, starting at macroblock 0.
  const int macroblocks = mb_cols_ * mb_rows_;
  int size = slices.size() > 1 ? slices[1].first_mb - slices[0].first_mb : macroblocks;
  bool uniform = !slices.empty() && slices[0].first_mb == 0 && size > 0;
  for (std::size_t i = 1; uniform && i < slices.size(); ++i) uniform = slices[i].first_mb - slices[i - 1].first_mb == size;
  if (uniform) uniform = macroblocks - slices.back().first_mb <= size;
  slice_mbs_ = uniform ? size : 0;
}

std::vector<RowSpan> PictureDamage::update(const PictureEvidence& e) {
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(height_px_), 0);
  // 1. Lost here: whole macroblock rows touched by a suspect range. (Their concealment, and
  // its deblocking past them, comes after the picture is decoded: see the end.)
  std::vector<RowSpan> lost;
  if (e.unplaced) {
    lost.push_back({0, height_px_});
  } else if (e.lost) {
    for (const auto& [first, end] : suspect_macroblocks(e, mb_cols_ * mb_rows_, slice_mbs_)) {
      if (end > first) lost.push_back({(first / mb_cols_) * kMbPx, ((end - 1) / mb_cols_ + 1) * kMbPx});
    }
  }
  for (const RowSpan& r : lost) mark(mask, r.v_begin_px, r.v_end_px);
  if (!e.lost && !e.unplaced) learn_layout(e.slices);
  // 2. Predicted from damage in any picture it may reference.
  const int refs = std::clamp(e.refs, 1, kMaxRefs);
  std::vector<std::uint8_t> reference(static_cast<std::size_t>(height_px_), 0);
  for (int i = 0; i < refs && i < static_cast<int>(history_.size()); ++i) {
    for (int v = 0; v < height_px_; ++v) reference[v] |= history_[i][v];
  }
  std::vector<std::uint8_t> inter(static_cast<std::size_t>(mb_cols_ * mb_rows_), 0);
  for (const BlockMotion& b : e.motion) {
    // Quarter-pixel luma vectors are eighth-pixel chroma vectors of the same value (4:2:0).
    const int scale = std::max(1, b.motion_scale);
    const int quarter = b.motion_y * 4 / scale;
    const int luma_whole = floor_div(quarter, 4), chroma_whole = floor_div(quarter, 8);
    const bool luma_fraction = quarter % 4 != 0, chroma_fraction = quarter % 8 != 0;
    const int top = b.dst_centre_y_px - b.height_px / 2;
    for (int v = std::max(top, 0); v < std::min(top + b.height_px, height_px_); ++v) {
      if (mask[v]) continue;
      // Luma: row v + m, or the filter's window around it.
      const int m = v + luma_whole;
      const bool luma = luma_fraction ? reads(reference, m - kFilterAbovePx, m + kFilterBelowPx) : reads(reference, m, m);
      // Chroma: chroma row c = floor(v / 2) + floor(vector), and c + 1 when fractional (the
      // bilinear filter); chroma row c is picture rows 2c and 2c + 1.
      const int c = v / 2 + chroma_whole;
      const bool chroma = reads(reference, 2 * c, 2 * (c + (chroma_fraction ? 1 : 0)) + 1);
      if (luma || chroma) mask[v] = 1;
    }
    const int col = std::clamp(b.dst_centre_x_px / kMbPx, 0, mb_cols_ - 1);
    const int row = std::clamp(b.dst_centre_y_px / kMbPx, 0, mb_rows_ - 1);
    inter[static_cast<std::size_t>(row * mb_cols_ + col)] = 1;
  }
  // 3. Intra macroblocks, top down so that damage carried within a slice is followed: one in
  // a macroblock row that holds damaged rows (predicted from a damaged left neighbour, or from
  // damaged rows of its own), or below a damaged row of its own slice, damages its whole row.
  std::vector<int> starts;
  for (const sdk::SliceSpan& s : e.slices) starts.push_back(s.first_mb);
  std::sort(starts.begin(), starts.end());
  for (int row = 0; row < mb_rows_; ++row) {
    const bool within = any(mask, row * kMbPx, (row + 1) * kMbPx);
    const bool above = row > 0 && mask[std::min(row * kMbPx, height_px_) - 1];
    if (!within && !above) continue;
    for (int col = 0; col < mb_cols_; ++col) {
      const int mb = row * mb_cols_ + col;
      if (inter[mb]) continue;
      // Same slice as the neighbour above: no slice begins after it and at or before this one.
      const auto it = std::upper_bound(starts.begin(), starts.end(), mb - mb_cols_);
      if (!within && it != starts.end() && *it <= mb) continue;
      mark(mask, row * kMbPx, (row + 1) * kMbPx);
      break;
    }
  }
  // The concealment's deblocking reaches a few rows past the concealed ones.
  for (const RowSpan& r : lost) mark(mask, r.v_begin_px - reach_px_, r.v_end_px + reach_px_);
  history_.push_front(mask);
  if (history_.size() > static_cast<std::size_t>(kMaxRefs)) history_.pop_back();
  (void)width_px_;
  return spans(mask);
}

}  // namespace shelfcross::tello
