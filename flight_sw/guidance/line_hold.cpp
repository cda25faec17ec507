#include "flight_sw/guidance/line_hold.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

namespace {
// Longer than any line_hold_window_s worth judging on (the validation caps it).
constexpr double kKeep_s = 10.0;
}  // namespace

double LineRoom::offset_y_m() const { return std::max(std::abs(front_K_m.y()), std::abs(back_K_m.y())); }
double LineRoom::offset_z_m() const { return std::max(std::abs(front_K_m.z()), std::abs(back_K_m.z())); }

// ---- Before the crossing: the quiet stretch's wander ----

void LineHoldMonitor::clear() {
  poses_.clear();
  across_mps_.clear();
  anchor_.reset();
}

void LineHoldMonitor::on_pose(TimeNs t_ns, const Eigen::Vector3d& p_K_m, double yaw_K_rad, bool quiet) {
  add(t_ns, p_K_m, yaw_K_rad, quiet, true);
}

void LineHoldMonitor::on_picture(TimeNs t_ns, const PoseEstimate* clean_K, const std::optional<OdometryFix>& fix,
                                 bool quiet, double carry_s) {
  if (clean_K) {
    add(t_ns, clean_K->p_FB_m(), clean_K->yaw_rad, quiet, true);
    // Only a quiet pose is carried: while a lateral command acts, the picture's latency
    // (0.12-0.35 s) puts the pose behind the odometry fix by the sideways speed times it.
    if (quiet && fix) anchor_ = Anchor{t_ns, *clean_K, *fix};
    return;
  }
  if (!quiet) return clear();
  if (!fix) return;
  if (const auto c = carried(t_ns, *fix, carry_s)) add(t_ns, c->first.p_FB_m(), c->first.yaw_rad, true, false);
}

std::optional<std::pair<PoseEstimate, TimeNs>> LineHoldMonitor::carried(TimeNs t_ns, const OdometryFix& fix,
                                                                        double carry_s) const {
  if (!anchor_ || ns_to_seconds(t_ns - anchor_->t_ns) > carry_s) return std::nullopt;
  const PoseEstimate moved = pose_after_motion(anchor_->pose_K, anchor_->fix.yaw_O_rad, fix.p_O_m - anchor_->fix.p_O_m,
                                               wrap_pi(fix.yaw_O_rad - anchor_->fix.yaw_O_rad));
  return std::make_pair(moved, anchor_->t_ns);
}

void LineHoldMonitor::add(TimeNs t_ns, const Eigen::Vector3d& p_K_m, double yaw_K_rad, bool quiet, bool measured) {
  yaw_K_rad_ = yaw_K_rad;
  if (!quiet) {  // the stretch ends: what came before it was moved on purpose
    clear();
    return;
  }
  poses_.push_back({t_ns, p_K_m.x(), p_K_m.y(), p_K_m.z(), yaw_K_rad, measured});
  // Only a window is ever judged; what is older than kKeep_s can go.
  const TimeNs keep_from_ns = t_ns - seconds_to_ns(kKeep_s);
  while (poses_.front().t_ns < keep_from_ns) poses_.pop_front();
  while (!across_mps_.empty() && across_mps_.front().first < keep_from_ns) across_mps_.pop_front();
}

void LineHoldMonitor::on_state(const StateRecord& s, bool quiet) {
  if (!quiet) return;
  air_.on_state(s.t_ns, s.vy_H_mps);
  if (poses_.empty() || s.t_ns < poses_.front().t_ns) return;
  // v_K = R_z(yaw_K) v_H: the across-line (y_K) component of the heading-frame velocity.
  const double across = std::sin(yaw_K_rad_) * s.vx_H_mps + std::cos(yaw_K_rad_) * s.vy_H_mps;
  across_mps_.emplace_back(s.t_ns, across);
}

namespace {

// The least-squares line v = a + b (t - t0) through (t_i, v_i): its slope b, half the spread
// (max - min) / 2 of the residuals r_i = v_i - a - b (t_i - t0), and the slope's standard
// error s / sqrt(sum (t_i - t_m)^2) sqrt(n / n_eff), s^2 = sum r_i^2 / (n - 2). The poses of a
// hover come 30 a second while the hold and the air move the vehicle over the autopilot's
// velocity lag and the gusts' second, so neighbouring residuals are alike and n of them know
// as much as n_eff independent ones: n_eff = n (1 - rho) / (1 + rho) for the residuals'
// lag-one correlation rho >= 0 (an AR(1) process's), and never more than one per velocity
// lag of the span (span / kVelocityLag_s, at least 2): a stretch of one lag shows one push,
// not its mean.
struct LineFit {
  double slope = 0.0;
  double half_spread = 0.0;
  double slope_error = 0.0;
};
LineFit fit_line(const std::vector<double>& t, const std::vector<double>& v) {
  const size_t n = t.size();
  const double span_s = t.back() - t.front();
  double st = 0.0, sv = 0.0;
  for (size_t i = 0; i < n; ++i) st += t[i], sv += v[i];
  const double tm = st / static_cast<double>(n), vm = sv / static_cast<double>(n);
  double stt = 0.0, stv = 0.0;
  for (size_t i = 0; i < n; ++i) stt += (t[i] - tm) * (t[i] - tm), stv += (t[i] - tm) * (v[i] - vm);
  LineFit f;
  f.slope = stt > 0.0 ? stv / stt : 0.0;
  std::vector<double> r(n);
  for (size_t i = 0; i < n; ++i) r[i] = v[i] - vm - f.slope * (t[i] - tm);
  const auto [r_min, r_max] = std::minmax_element(r.begin(), r.end());
  f.half_spread = 0.5 * (*r_max - *r_min);
  if (n < 3 || stt <= 0.0) return f;
  double rr = 0.0, lag = 0.0;
  for (size_t i = 0; i < n; ++i) {
    rr += r[i] * r[i];
    if (i > 0) lag += r[i] * r[i - 1];
  }
  const double rho = rr > 0.0 ? std::clamp(lag / rr, 0.0, 0.95) : 0.0;
  const double n_eff = std::min(static_cast<double>(n) * (1.0 - rho) / (1.0 + rho),
                                std::max(2.0, span_s / kVelocityLag_s));
  const double variance = rr / static_cast<double>(n - 2);
  f.slope_error = std::sqrt(variance / stt * static_cast<double>(n) / n_eff);
  return f;
}

}  // namespace

LineWander LineHoldMonitor::wander(TimeNs now_ns, double window_s) const {
  const TimeNs from_ns = now_ns - seconds_to_ns(window_s);
  LineWander w;
  w.air_rms_mps = air_.rms_mps(now_ns);
  w.air_error_mps = air_.error_mps(now_ns);
  auto first = poses_.begin();
  while (first != poses_.end() && first->t_ns < from_ns) ++first;
  if (first == poses_.end()) return w;
  double yaw_sum = 0.0;
  for (auto it = first; it != poses_.end(); ++it) {
    yaw_sum += it->yaw_rad;
    if (it->measured) ++w.measured;
  }
  w.poses = static_cast<int>(poses_.end() - first);
  const double yaw = yaw_sum / w.poses, c = std::cos(yaw), s = std::sin(yaw);
  std::vector<double> t, across, up;
  for (auto it = first; it != poses_.end(); ++it) {
    t.push_back(ns_to_seconds(it->t_ns - first->t_ns));
    across.push_back(it->y_m * c - it->x_m * s);  // y' across the heading
    up.push_back(it->z_m);
  }
  w.span_s = t.back();
  const LineFit fy = fit_line(t, across), fz = fit_line(t, up);
  w.half_spread_y_m = fy.half_spread;
  w.drift_y_mps = fy.slope;
  w.drift_error_y_mps = fy.slope_error;
  w.half_spread_z_m = fz.half_spread;
  // The largest mean of kSpeedRecords consecutive quiet records (all of them, if fewer).
  std::vector<double> v;
  for (const auto& [ts, across] : across_mps_) {
    if (ts >= first->t_ns) v.push_back(across);
  }
  const size_t n = std::min(v.size(), static_cast<size_t>(kSpeedRecords));
  for (size_t i = 0; n > 0 && i + n <= v.size(); ++i) {
    double sum = 0.0;
    for (size_t j = i; j < i + n; ++j) sum += v[j];
    w.across_speed_mps = std::max(w.across_speed_mps, std::abs(sum) / static_cast<double>(n));
  }
  return w;
}

void AirMemory::on_state(TimeNs t_ns, double vy_H_mps) {
  vy_.emplace_back(t_ns, vy_H_mps);
  while (ns_to_seconds(t_ns - vy_.front().first) > kAirMemory_s) vy_.pop_front();
}

// The products of consecutive remembered records (file comment, "air"), their mean and its
// standard error.
AirMemory::Power AirMemory::power(TimeNs now_ns) const {
  double sum = 0.0, sum_sq = 0.0;
  int records = 0, pairs = 0;
  const std::pair<TimeNs, double>* last = nullptr;
  for (const auto& r : vy_) {
    if (ns_to_seconds(now_ns - r.first) > kAirMemory_s) continue;
    ++records;
    if (last && ns_to_seconds(r.first - last->first) <= kAirPairGap_s) {
      const double product = last->second * r.second;
      sum += product;
      sum_sq += product * product;
      ++pairs;
    }
    last = &r;
  }
  Power p;
  if (records < kAirMinRecords || pairs < 2) return p;
  p.measured = true;
  p.mean = sum / pairs;
  const double variance = std::max(0.0, (sum_sq - pairs * p.mean * p.mean) / (pairs - 1));
  p.standard_error = std::sqrt(variance / pairs);
  return p;
}

double AirMemory::rms_mps(TimeNs now_ns) const {
  const Power p = power(now_ns);
  return p.measured ? std::sqrt(std::max(0.0, p.mean)) : 0.0;
}

double AirMemory::error_mps(TimeNs now_ns) const {
  const Power p = power(now_ns);
  if (!p.measured) return 0.0;
  return std::sqrt(std::max(0.0, p.mean + p.standard_error)) - std::sqrt(std::max(0.0, p.mean));
}

LineHoldForecast forecast_line_hold(const MissionParams& m, const LineWander& w, double blind_s) {
  LineHoldForecast f;
  f.measured = w.poses >= kLineHoldMinPoses && w.measured >= kLineHoldMinMeasured && w.span_s >= m.line_hold.line_hold_min_span_s;
  if (!f.measured) return f;
  f.span_s = w.span_s;
  // Random-walk growth of the spread from the quiet stretch to the blind crossing (never below
  // the spread seen), and the carry of the speed seen (file comment).
  const double growth = std::sqrt(std::max(1.0, blind_s / w.span_s));
  // The wander across: the window's, or the air remembered where that reaches further.
  const double wander_y = w.half_spread_y_m * growth, air_y = kAirReach_s * w.air_rms_mps;
  if (air_y > wander_y) f.air_rms_mps = w.air_rms_mps;
  // The drift goes on for the whole crossing. Flown out (trim_drift): only what the hover showed
  // beyond one standard error of it, sign(d) max(0, |d| - se_d), so that a slope the air made
  // on a short stretch is not flown as a drift. It is still forecast whole: the trim centres the
  // line where the drift holds, and the forecast covers a trim as wrong as the drift is large
  // (a drift that changes).
  if (m.line_hold.trim_drift) {
    f.drift_trim_y_mps = std::copysign(std::max(0.0, std::abs(w.drift_y_mps) - w.drift_error_y_mps), w.drift_y_mps);
  }
  f.y_m = std::max(wander_y, air_y) + std::abs(w.drift_y_mps) * blind_s + w.across_speed_mps * kVelocityLag_s;
  f.z_m = w.half_spread_z_m * growth;
  // Its own error: the pose's, and how much further the air's reach goes at one standard error
  // more of the air's rms (where that decides the wander).
  const double air_up_y = kAirReach_s * (w.air_rms_mps + w.air_error_mps);
  // And the drift's: its slope's standard error carried over the blind crossing.
  f.error_y_m = kPoseError_m + std::max(wander_y, air_up_y) - std::max(wander_y, air_y) + w.drift_error_y_mps * blind_s;
  f.error_z_m = kPoseError_m;
  return f;
}

double line_hold_keep_m(const MissionParams& m, double error_m) {
  return std::max(m.crossing_margin_m, m.line_hold.separation_min_m + error_m);
}

double blind_crossing_s(const FlightConfig& config, double range_m) {
  const double flown_m = range_m + config.shelf.depth_m + config.mission.vehicle_size_m.x();
  return flown_m / config.control.crossing_speed_mps;
}

double range_hold_climb_m(const FlightConfig& config, CellIndex target, double cell_centre_h_m) {
  const CrossingParams& c = config.mission.crossing;
  if (c.height_hold_range_blend <= 0.0) return 0.0;
  const double step_m = std::max(0.0, cell_centre_h_m - 0.5 * cell_opening_m(config.shelf, target).y());
  const double over_s = (config.shelf.depth_m + config.mission.vehicle_size_m.x()) / config.control.crossing_speed_mps;
  return c.height_hold_range_blend * step_m * (1.0 - std::exp(-over_s / c.height_hold_time_constant_s));
}

// ---- The room ----

LineRoom line_room(const FlightConfig& config, CellIndex target, const PoseEstimate& pose) {
  const MissionParams& m = config.mission;
  const Eigen::Vector2d opening = cell_opening_m(config.shelf, target);
  const double psi = std::abs(pose.yaw_rad);
  // Footprint across the opening of a vehicle turned by psi (its heading is held).
  const double footprint = m.vehicle_size_m.y() * std::cos(psi) + m.vehicle_size_m.x() * std::sin(psi);
  LineRoom room;
  room.room_y_m = 0.5 * (opening.x() - footprint);
  room.room_z_m = 0.5 * (opening.y() - m.vehicle_size_m.z());
  room.tol_y_m = room.room_y_m - m.crossing_margin_m;
  room.tol_z_m = room.room_z_m - m.crossing_margin_m;
  const Eigen::Vector3d p = pose.p_FB_m();
  const Eigen::Vector3d d = crossing_direction_K(config.shelf, pose);
  // Where the crossing line meets the front and back faces.
  const auto at = [&](double x) -> Eigen::Vector3d { return p + d * ((x - p.x()) / d.x()); };
  room.front_K_m = at(0.0);
  room.back_K_m = at(config.shelf.depth_m);
  return room;
}

// ---- During the crossing: the watch ----

CrossingWatchPlan plan_crossing_watch(const FlightConfig& config, const LineRoom& room, const Eigen::Vector3d& p_K_m,
                                      const Eigen::Vector3d& d_K) {
  const MissionParams& m = config.mission;
  const KnownShelf& sh = config.shelf;
  CrossingWatchPlan plan;
  // The frame's nearest part: the tags, tag_offset_m in front of the front bars' centre plane,
  // the bars half their thickness in front of it, whichever sticks out more.
  const double x_front_K = -std::max(sh.tag_offset_m, 0.5 * sh.post_thickness_m);
  // Along the line's horizontal part, from the start to where the vehicle's front meets it.
  const double to_front_x = x_front_K - p_K_m.x() - 0.5 * m.vehicle_size_m.x();
  plan.stop_before_m = std::max(0.0, to_front_x / d_K.x() * d_K.head<2>().norm());
  // A stop is forecast from the odometry (a few state records): what it leaves must keep the
  // separation minimum clear of the frame, beyond the error of the line it is measured from.
  const double keep = m.line_hold.separation_min_m + kPoseError_m;
  plan.slack_y_m = room.room_y_m - keep - room.offset_y_m();
  plan.slack_z_m = room.room_z_m - keep;
  return plan;
}

CrossingWatchVerdict crossing_watch(const CrossingEnd& end, const CrossingWatchPlan& plan, const MissionParams& m,
                                    const Eigen::Vector3d& p_O_m, const Eigen::Vector2d& v_O_mps,
                                    double height_above_cell_m, double vz_mps) {
  const Eigen::Vector2d across_axis(-end.axis_O.y(), end.axis_O.x());
  const Eigen::Vector2d flown = p_O_m.head<2>() - end.start_O_m;
  CrossingWatchVerdict v;
  // Where the vehicle is carried before a change of command takes hold: its speed times the
  // autopilot's lag (horizontal kVelocityLag_s, vertical vertical_lag_s).
  v.across_m = flown.dot(across_axis) + v_O_mps.dot(across_axis) * kVelocityLag_s;
  v.height_m = height_above_cell_m + vz_mps * m.crossing.vertical_lag_s;
  const double stops_at = flown.dot(end.axis_O) + std::max(0.0, v_O_mps.dot(end.axis_O)) * kVelocityLag_s;
  if (stops_at >= plan.stop_before_m) return v;  // committed: stopping would leave it in the frame
  v.back_out = std::abs(v.across_m) > plan.slack_y_m || std::abs(v.height_m) > plan.slack_z_m;
  return v;
}

std::string air_text(const LineHoldForecast& f) {
  if (f.air_rms_mps <= 0.0) return {};
  char text[64];
  std::snprintf(text, sizeof text, " (the air remembered: %.3f m/s rms)", f.air_rms_mps);
  return text;
}

std::string centimetres_text(double length_m) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f cm", 100.0 * length_m);
  return text;
}

}  // namespace shelfcross::flight_sw
