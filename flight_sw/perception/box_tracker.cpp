#include "flight_sw/perception/box_tracker.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::flight_sw {

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

}  // namespace shelfcross::flight_sw
