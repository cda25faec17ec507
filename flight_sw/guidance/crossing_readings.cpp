#include "flight_sw/guidance/crossing_readings.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::flight_sw {

namespace {
// Between records further apart than this (the link lost several) the vertical speed's
// integral and the range's change are not compared: too much may have happened between them.
constexpr double kMaxGap_s = 0.35;
}  // namespace

void CrossingReadings::on_state(const StateRecord& s, bool flying) {
  if (!first_) {
    first_ = last_ = s;
    return;
  }
  const double dt = ns_to_seconds(s.t_ns - last_->t_ns);
  if (dt <= 0.0) return;
  // The vertical speed of the interval: the mean of its two records' (each a 0.1 m/s step).
  // Over one surface the range's change is the climb; across a step, or without a range, the
  // vertical speed's.
  const double vz = 0.5 * (s.vz_H_mps + last_->vz_H_mps), dz_vz = vz * std::min(dt, kMaxGap_s);
  const bool ranged = dt <= kMaxGap_s && s.tof_m && last_->tof_m;
  const bool step = ranged && std::abs(*s.tof_m - *last_->tof_m - dz_vz) > kRangeStep_m;
  range_stepped_ = range_stepped_ || step;
  climbed_m_ += ranged && !step ? *s.tof_m - *last_->tof_m : dz_vz;
  const double o = (s.height_m - first_->height_m) - climbed_m_;
  if (range_stepped_ && std::abs(o) >= kHoldOffsetSeen_m) offset_seen_ = true;
  offsets_.emplace_back(s.t_ns, o);
  if (offsets_.size() > static_cast<size_t>(kRateRecords) + 1) offsets_.pop_front();
  const bool vps_reads_nothing = s.vx_H_mps == 0.0 && s.vy_H_mps == 0.0;
  vps_zero_records_ = flying && vps_reads_nothing ? vps_zero_records_ + 1 : 0;
  if (vps_zero_records_ >= kVpsLostRecords) vps_lost_ = true;
  // Flown blind: the interval the odometry adds nothing for, at the speed last read.
  if (flying && vps_reads_nothing) {
    if (const std::optional<double> v = speed_mps()) blind_m_ += *v * dt;
  } else if (flying) {
    speeds_mps_.push_back(std::hypot(s.vx_H_mps, s.vy_H_mps));
    if (speeds_mps_.size() > static_cast<size_t>(kBlindSpeedRecords)) speeds_mps_.pop_front();
  }
  last_ = s;
}

std::optional<double> CrossingReadings::speed_mps() const {
  if (speeds_mps_.size() < static_cast<size_t>(kBlindSpeedRecords)) return std::nullopt;
  double sum = 0.0;
  for (double v : speeds_mps_) sum += v;
  return sum / static_cast<double>(speeds_mps_.size());
}

double CrossingReadings::hold_offset_rate_mps() const {
  if (!offset_seen_ || offsets_.size() < 2) return 0.0;
  const double dt = ns_to_seconds(offsets_.back().first - offsets_.front().first);
  return dt > 0.0 ? (offsets_.back().second - offsets_.front().second) / dt : 0.0;
}

double CrossingReadings::hold_offset_m() const {
  if (!offset_seen_) return 0.0;
  return (last_->height_m - first_->height_m) - climbed_m_;
}

}  // namespace shelfcross::flight_sw
