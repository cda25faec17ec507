#include "flight_sw/navigation/odometry.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::flight_sw {

namespace {
// A crossing timed (state records stale) or ended by odometry never lasts longer than this
// times its timed duration: bounds the overshoot of an odometry that under-reads.
constexpr double kCrossMaxOverTime = 1.5;
// The cell centre's height: the median of the last kCellHeightSamples samples, at least
// kMinCellHeightSamples of them.
constexpr size_t kCellHeightSamples = 15;
constexpr size_t kMinCellHeightSamples = 3;
// The forward gain's lag (a video latency plus the autopilot's velocity lag) and the
// commanded displacement it waits for.
constexpr double kGainLag_s = 0.2 + kVelocityLag_s, kMinCommanded_m = 0.8;
}  // namespace

// ---- State odometry ----

void StateOdometry::on_state(const StateRecord& s) {
  // p_O += R_z(yaw) v_H dt (rectangle rule on the newer record), z = height.
  if (t_ns_ && s.t_ns > *t_ns_) {
    const double dt = std::min(ns_to_seconds(s.t_ns - *t_ns_), 1.0);
    const double c = std::cos(s.yaw_rad), sn = std::sin(s.yaw_rad);
    p_O_m_.x() += (c * s.vx_H_mps - sn * s.vy_H_mps) * dt;
    p_O_m_.y() += (sn * s.vx_H_mps + c * s.vy_H_mps) * dt;
  }
  t_ns_ = std::max(t_ns_.value_or(s.t_ns), s.t_ns);
  p_O_m_.z() = s.height_m;
}

double crossing_progress_m(const CrossingEnd& end, const Eigen::Vector3d& p_O_m) {
  return (p_O_m.head<2>() - end.start_O_m).dot(end.axis_O);
}

bool crossing_flown(const CrossingEnd& end, TimeNs elapsed_ns, std::optional<double> progress_m) {
  if (elapsed_ns >= static_cast<TimeNs>(kCrossMaxOverTime * static_cast<double>(end.timed_ns))) return true;
  if (!progress_m) return elapsed_ns >= end.timed_ns;
  return *progress_m >= end.line_m;
}

// ---- The forward speed gain ----

void ForwardGainEstimator::restart() {
  start_.reset();
  commanded_m_.clear();
  last_ns_.reset();
}

void ForwardGainEstimator::on_command_held(TimeNs t_ns, double vx_B_mps, double stick_scale) {
  // The forward displacement commanded so far, in nominal sticks: the last command held since
  // the last frame, at the scale it was sent at.
  if (last_ns_) {
    const double d = commanded_m_.empty() ? 0.0 : commanded_m_.back().second;
    commanded_m_.emplace_back(t_ns, d + vx_B_mps * stick_scale * ns_to_seconds(t_ns - *last_ns_));
  }
  last_ns_ = t_ns;
  stick_scale_ = stick_scale;
}

// D at t_ns, held before the first sample.
double ForwardGainEstimator::commanded_at(TimeNs t_ns) const {
  double d = 0.0;
  for (const auto& [t, dd] : commanded_m_) {
    if (t > t_ns) break;
    d = dd;
  }
  return d;
}

void ForwardGainEstimator::on_pose(TimeNs t_ns, double x_K_m) {
  if (!start_) {
    start_ = std::make_pair(t_ns, x_K_m);
    return;
  }
  const TimeNs lag_ns = seconds_to_ns(kGainLag_s);
  const double commanded = commanded_at(t_ns - lag_ns) - commanded_at(start_->first - lag_ns);
  if (commanded < kMinCommanded_m) return;
  gain_ = std::clamp((x_K_m - start_->second) / commanded, 0.5, 2.0);
}

// ---- The cell centre's height in the state height's frame ----

void CellHeightEstimator::on_state(const StateRecord& s) {
  if (std::abs(s.vz_H_mps) > kVerticallyStill_mps) vertical_motion_ns_ = s.t_ns;
}

bool CellHeightEstimator::vertically_still_for(TimeNs now_ns, double vertical_lag_s) const {
  return !(vertical_motion_ns_ && ns_to_seconds(now_ns - *vertical_motion_ns_) < vertical_lag_s);
}

void CellHeightEstimator::sample(double state_height_m, double z_K_m) {
  samples_m_.push_back(cell_centre_height_m(state_height_m, z_K_m));
  if (samples_m_.size() > kCellHeightSamples) samples_m_.erase(samples_m_.begin());
}

std::optional<double> CellHeightEstimator::measured_m() const {
  if (samples_m_.size() < kMinCellHeightSamples) return std::nullopt;
  std::vector<double> v = samples_m_;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace shelfcross::flight_sw
