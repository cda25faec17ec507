#include "identify/identification.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "shelfcross/random.hpp"

namespace shelfcross::identify {
namespace {

constexpr double kWindowBefore_s = 1.0, kWindowAfter_s = 3.0;
// Integral observations (height, heading) get an offset per pulse or doublet: a new segment in
// the middle of every hover of at least this long between the axis's deflections. Each segment
// holds its pulse with hover on both sides, so the pulse's displacement and lags stay in it;
// what goes is the level one pulse leaves for the next, which the slow drift of a height in
// gusts (1 to 3 cm over the manoeuvre's 25 s in tello-sim) blurs and which, left in one offset,
// stays in the residuals as a trend and widens the intervals.
constexpr double kSegmentGap_s = 1.0;

int stick_index(Axis a) {
  switch (a) {
    case Axis::forward: return 1;
    case Axis::lateral: return 0;
    case Axis::vertical: return 2;
    case Axis::yaw: return 3;
  }
  return 0;
}
// Stick sign to this project's frames: a right -> y left, d clockwise -> yaw counter-clockwise.
double stick_sign(Axis a) { return a == Axis::lateral || a == Axis::yaw ? -1.0 : 1.0; }

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

LinkFigures link_figures(const FlightRecord& r) {
  LinkFigures f;
  const std::vector<TimeNs> sent = state_send_times(r);
  for (size_t i = 0; i < sent.size(); ++i) {
    const double early_s = ns_to_seconds(r.states[i].t_ns - sent[i]);
    f.held_up_states += early_s >= 0.010 ? 1 : 0;
    f.held_up_max_s = std::max(f.held_up_max_s, early_s);
  }
  f.state_records = static_cast<int>(r.states.size());
  f.bad_states = r.bad_states;
  std::vector<double> periods;
  for (size_t i = 1; i < r.states.size(); ++i) periods.push_back(ns_to_seconds(r.states[i].t_ns - r.states[i - 1].t_ns));
  f.state_period_p50_s = percentile(periods, 0.5);
  f.state_period_p95_s = percentile(periods, 0.95);
  f.state_gap_max_s = periods.empty() ? 0.0 : *std::max_element(periods.begin(), periods.end());
  f.frames = static_cast<int>(r.frames.size());
  std::vector<double> frame_periods, decode, take;
  for (size_t i = 0; i < r.frames.size(); ++i) {
    const FrameStamps& fr = r.frames[i];
    f.damaged_frames += fr.damaged ? 1 : 0;
    if (i > 0) frame_periods.push_back(ns_to_seconds(fr.rx_ns - r.frames[i - 1].rx_ns));
    decode.push_back(ns_to_seconds(fr.handed_ns - fr.rx_ns));
    take.push_back(ns_to_seconds(fr.taken_ns - fr.handed_ns));
  }
  f.frame_period_p50_s = percentile(frame_periods, 0.5);
  f.frame_period_p95_s = percentile(frame_periods, 0.95);
  f.rx_to_handed_p50_s = percentile(decode, 0.5);
  f.rx_to_handed_p95_s = percentile(decode, 0.95);
  f.handed_to_taken_p50_s = percentile(take, 0.5);
  f.handed_to_taken_p95_s = percentile(take, 0.95);
  return f;
}

// The model-error allowance (identification.hpp), relative to the value, per axis: {gain, time
// constant}.
constexpr std::array<std::array<double, 2>, 4> kModelAllowance = {{
    {kAllowanceVelocityGain, kAllowanceTimeConstant},   // forward
    {kAllowanceVelocityGain, kAllowanceTimeConstant},   // lateral
    {kAllowanceIntegralGain, kAllowanceTimeConstant},   // vertical
    {kAllowanceIntegralGain, kAllowanceTimeConstant}}};  // yaw

// Adds an absolute allowance to the interval: a bias anywhere within +-margin (uniform, standard
// deviation margin / sqrt(3)) is independent of the bootstrap's spread, so each half-width
// becomes the root sum of squares of the bootstrap's and 1.96 margin / sqrt(3).
void widen(Interval& iv, double margin) {
  constexpr double kUniformAt95 = 1.96 / 1.7320508075688772;
  iv.margin += margin;
  iv.lo = iv.value - std::hypot(iv.value - iv.lo, kUniformAt95 * margin);
  iv.hi = iv.value + std::hypot(iv.hi - iv.value, kUniformAt95 * margin);
}

// Replicate-wise inverse-variance weighted combination of intervals (see the header).
std::optional<Interval> combine(const std::vector<const Interval*>& parts, const std::vector<double>& scale) {
  std::vector<double> w;
  double total = 0.0;
  for (const Interval* p : parts) {
    const double sd = std::max(p->stddev, 1e-9 * std::max(1.0, std::abs(p->value)));
    w.push_back(1.0 / (sd * sd));
    total += w.back();
  }
  if (parts.empty() || !(total > 0.0)) return std::nullopt;
  double value = 0.0;
  for (size_t i = 0; i < parts.size(); ++i) value += w[i] / total * parts[i]->value * scale[i];
  size_t reps = parts.front()->replicates.size();
  for (const Interval* p : parts) reps = std::min(reps, p->replicates.size());
  double margin = 0.0;  // a bound on each part's model error bounds their weighted mean's
  for (size_t i = 0; i < parts.size(); ++i) margin += w[i] / total * std::abs(scale[i]) * parts[i]->margin;
  std::vector<double> combined(reps, 0.0);
  // Replicate b of each axis comes from that axis's own independent resampling: pairing them
  // by index is a draw from the joint bootstrap distribution.
  for (size_t b = 0; b < reps; ++b) {
    for (size_t i = 0; i < parts.size(); ++i) combined[b] += w[i] / total * parts[i]->replicates[b] * scale[i];
  }
  Interval iv = interval_of(value, std::move(combined));
  widen(iv, margin);
  return iv;
}

// Each axis its own resampling stream: the seed mixed with the axis.
std::uint64_t axis_seed(const IdentifyOptions& o, size_t axis) { return mix64(o.seed + 0x1D0 + axis); }

}  // namespace

const char* axis_name(Axis a) {
  switch (a) {
    case Axis::forward: return "forward";
    case Axis::lateral: return "lateral";
    case Axis::vertical: return "vertical";
    case Axis::yaw: return "yaw";
  }
  return "?";
}

const char* axis_gain_unit(Axis a) { return a == Axis::yaw ? "rad/s" : "m/s"; }

TrackingLoop tracking_loop(Axis axis, const plant::AutopilotParams& P, const plant::VehicleParams& V) {
  TrackingLoop L;
  L.step_s = 1.0 / P.rate_hz;
  switch (axis) {
    case Axis::forward:
    case Axis::lateral:
      L.kind = TrackingLoop::Kind::acceleration;
      L.pos_gain_per_s = P.loops.pos_gain_per_s;
      L.vel_gain_per_s = P.loops.vel_gain_per_s;
      L.vel_integral_gain_per_s2 = P.loops.vel_integral_gain_per_s2;
      L.att_gain_per_s = P.loops.att_gain_per_s;
      L.rate_gain_per_s = P.loops.rate_gain_per_s;
      L.drag_per_s = V.linear_drag_Ns_per_m.x() / V.mass_kg;
      break;
    case Axis::vertical:
      L.kind = TrackingLoop::Kind::acceleration;
      L.pos_gain_per_s = P.loops.pos_gain_z_per_s;
      L.vel_gain_per_s = P.loops.vel_gain_z_per_s;
      L.vel_integral_gain_per_s2 = P.loops.vel_integral_gain_per_s2;
      L.lag_s = V.motor_time_constant_s;  // thrust is the motors' alone
      L.drag_per_s = V.linear_drag_Ns_per_m.z() / V.mass_kg;
      break;
    case Axis::yaw:
      L.kind = TrackingLoop::Kind::rate;
      L.pos_gain_per_s = P.loops.yaw_gain_per_s;
      L.rate_gain_per_s = P.loops.yaw_rate_gain_per_s;
      L.rate_integral_gain_per_s2 = P.loops.rate_integral_gain_per_s2;
      break;
  }
  return L;
}

AxisRecord axis_record(const FlightRecord& r, Axis axis, int min_stick, int* windows) {
  AxisRecord rec;
  rec.observation = axis == Axis::vertical || axis == Axis::yaw ? Observation::integral : Observation::direct;
  if (windows) *windows = 0;
  if (!r.takeoff_ok_ns) return rec;
  const TimeNs t0 = *r.takeoff_ok_ns;
  const TimeNs t_end = r.land_sent_ns.value_or(r.end_ns);
  const int idx = stick_index(axis);
  const double sign = stick_sign(axis);
  // The input: the drone flies the newest rc it received; it ignored them before the takeoff's ok.
  std::vector<std::pair<double, double>> active;  // (from, to) of deflections
  std::vector<double> boundaries;                  // integral observations: between pulses
  double last_deflected = -1e9;
  for (size_t i = 0; i < r.rc.size(); ++i) {
    const RcSent& rc = r.rc[i];
    if (rc.t_ns < t0 || rc.t_ns > t_end) continue;
    const double t = ns_to_seconds(rc.t_ns - t0);
    const double u = sign * rc.sticks[idx] / 100.0;
    if (rec.input.u.empty() || rec.input.u.back() != u) {
      rec.input.t_s.push_back(t);
      rec.input.u.push_back(u);
    }
    if (std::abs(rc.sticks[idx]) >= min_stick) {
      const double until = i + 1 < r.rc.size() ? ns_to_seconds(r.rc[i + 1].t_ns - t0) : t;
      if (t - last_deflected >= kSegmentGap_s) boundaries.push_back(0.5 * (t + last_deflected));
      last_deflected = until;
      if (!active.empty() && t - active.back().second < kWindowBefore_s + kWindowAfter_s) {
        active.back().second = until;
      } else {
        active.push_back({t, until});
      }
    }
  }
  if (windows) *windows = static_cast<int>(active.size());
  if (active.empty()) return rec;
  const double flight_end_s = ns_to_seconds(t_end - t0);
  // Heading unwrapped over the whole record (the state's yaw is in (-pi, pi]).
  double unwrap = 0.0, last_yaw = 0.0;
  bool first = true;
  const std::vector<TimeNs> sent = state_send_times(r);
  for (size_t k = 0; k < r.states.size(); ++k) {
    const StateRecord& s = r.states[k];
    if (!first) {
      const double step = s.yaw_rad - last_yaw;
      if (step > std::numbers::pi) unwrap -= 2.0 * std::numbers::pi;
      if (step < -std::numbers::pi) unwrap += 2.0 * std::numbers::pi;
    }
    first = false;
    last_yaw = s.yaw_rad;
    const double t = ns_to_seconds(sent[k] - t0);
    if (t < 0.5 || t > flight_end_s) continue;  // settle after the takeoff manoeuvre
    for (size_t w = 0; w < active.size(); ++w) {
      if (t < active[w].first - kWindowBefore_s || t > active[w].second + kWindowAfter_s) continue;
      double y = 0.0;
      switch (axis) {
        case Axis::forward: y = s.vx_H_mps; break;
        case Axis::lateral: y = s.vy_H_mps; break;
        case Axis::vertical: y = s.height_m; break;
        case Axis::yaw: y = s.yaw_rad + unwrap; break;
      }
      // Direct observations: a segment per window (for the bootstrap's continuity); integral
      // ones: a segment (an offset) per pulse or doublet, from the middle of the hover before it
      // to the middle of the hover after it.
      const int segment = rec.observation == Observation::integral
                              ? static_cast<int>(std::upper_bound(boundaries.begin(), boundaries.end(), t) - boundaries.begin())
                              : static_cast<int>(w);
      rec.t_s.push_back(t);
      rec.y.push_back(y);
      rec.segment.push_back(segment);
      break;
    }
  }
  // Segments numbered 0.. in order of the samples (some boundaries have none between them).
  const std::vector<int> raw = rec.segment;
  int segments = 0;
  for (size_t k = 0; k < raw.size(); ++k) {
    if (k == 0 || raw[k] != raw[k - 1]) ++segments;
    rec.segment[k] = segments - 1;
  }
  rec.segments = std::max(segments, 1);
  return rec;
}

std::optional<Interval> gain_scale(const Identification& id, const plant::AutopilotParams& nominal) {
  std::vector<const Interval*> parts;
  std::vector<double> scales;
  for (const AxisResult& a : id.axes) {
    if (!a.identified) continue;
    const double n = a.axis == Axis::yaw        ? nominal.rc_yaw_radps_at_100
                     : a.axis == Axis::vertical ? nominal.rc_vertical_mps_at_100
                                                : nominal.rc_horizontal_mps_at_100;
    parts.push_back(&a.id.gain);
    scales.push_back(1.0 / n);
  }
  return combine(parts, scales);
}

Identification identify_flight(const FlightRecord& r, const IdentifyOptions& o) {
  if (!r.takeoff_ok_ns) {
    throw std::invalid_argument(r.source + ": no flight: the log holds no takeoff acknowledged with 'ok'");
  }
  Identification id;
  id.source = r.source;
  id.options = o;
  id.flight_s = ns_to_seconds(r.land_sent_ns.value_or(r.end_ns) - *r.takeoff_ok_ns);
  id.link = link_figures(r);
  int identified = 0;
  // The dead time is the link's (the command's way to the drone, the state record's way back;
  // the onboard lags are the tracking loops'): one for all axes. Each axis is fitted with a
  // dead time of its own first; the link's is their inverse-variance weighted combination,
  // replicate by replicate (the integral axes resolve the response finely but trade the dead
  // time against the time constant; the velocity axes separate the two but read in 0.1 m/s:
  // neither alone pins it). The integral axes (height, heading) are then refitted with it and
  // its replicates, so that its uncertainty passes on to their time constants; the velocity
  // axes keep their own fit, whose intervals hold their own dead time's uncertainty.
  for (size_t i : {0u, 1u, 2u, 3u}) {
    AxisResult& a = id.axes[i];
    a.axis = kAxes[i];
    a.record = axis_record(r, a.axis, o.min_stick, &a.windows);
    a.record.loop = tracking_loop(a.axis, o.autopilot, o.vehicle);
    // The SDK's velocities are integer dm/s: coarse against the calibration's 0.2-0.4 m/s.
    if (a.record.observation == Observation::direct) a.record.quantum = 0.1;
    if (a.windows == 0) {
      a.why_not = "its stick never moved by " + std::to_string(o.min_stick) + " or more while flying";
      continue;
    }
    if (static_cast<int>(a.record.y.size()) < o.min_samples) {
      a.why_not = "only " + std::to_string(a.record.y.size()) + " state records while its stick moved (" +
                  std::to_string(o.min_samples) + " needed)";
      continue;
    }
    a.id = identify_axis(a.record, o.bootstrap_replicates, axis_seed(o, i), o.block_s, o.bounds);
    a.identified = true;
    ++identified;
  }
  std::optional<Interval> link_delay;
  {
    std::vector<const Interval*> parts;
    for (const AxisResult& a : id.axes) {
      if (a.identified) parts.push_back(&a.id.delay_s);
    }
    link_delay = combine(parts, std::vector<double>(parts.size(), 1.0));
  }
  if (link_delay && identified > 1) {
    for (size_t i : {2u, 3u}) {
      AxisResult& a = id.axes[i];
      if (!a.identified) continue;
      FitBounds bounds = o.bounds;
      bounds.delay_min_s = bounds.delay_max_s = link_delay->value;
      a.id = identify_axis(a.record, o.bootstrap_replicates, axis_seed(o, i), o.block_s, bounds, &link_delay->replicates);
    }
  }
  for (size_t i = 0; i < id.axes.size(); ++i) {
    AxisResult& a = id.axes[i];
    if (!a.identified) continue;
    widen(a.id.gain, kModelAllowance[i][0] * std::abs(a.id.gain.value));
    const double tau_margin = kModelAllowance[i][1] * a.id.tau_s.value;
    widen(a.id.tau_s, a.axis == Axis::yaw ? std::max(tau_margin, kAllowanceYawTimeConstant_s) : tau_margin);
  }
  if (identified == 0) {
    throw std::invalid_argument(r.source + ": no axis could be identified: no stick moved while flying (fly the "
                                           "calibration manoeuvre: tello_pilot --fly-calibration)");
  }
  auto axis = [&](Axis a) -> const AxisResult& { return id.axes[static_cast<size_t>(a)]; };
  auto put = [&](const std::string& name, std::vector<const Interval*> parts, std::vector<double> scale) {
    if (auto c = combine(parts, scale)) id.parameters[name] = std::move(*c);
  };
  std::vector<const Interval*> h_gain, h_tau;
  std::vector<double> h_ones;
  for (Axis a : {Axis::forward, Axis::lateral}) {
    if (!axis(a).identified) continue;
    h_gain.push_back(&axis(a).id.gain);
    h_tau.push_back(&axis(a).id.tau_s);
    h_ones.push_back(1.0);
  }
  put("rc_horizontal_mps_at_100", h_gain, h_ones);
  put("velocity_time_constant_s", h_tau, h_ones);
  if (axis(Axis::vertical).identified) {
    put("rc_vertical_mps_at_100", {&axis(Axis::vertical).id.gain}, {1.0});
    put("vertical_time_constant_s", {&axis(Axis::vertical).id.tau_s}, {1.0});
  }
  if (axis(Axis::yaw).identified) {
    put("rc_yaw_radps_at_100", {&axis(Axis::yaw).id.gain}, {1.0});
    put("yaw_time_constant_s", {&axis(Axis::yaw).id.tau_s}, {1.0});
  }
  if (auto scale = gain_scale(id, o.autopilot)) id.parameters["rc_gain_scale"] = std::move(*scale);
  if (link_delay) id.parameters["response_delay_s"] = *link_delay;
  SensesOptions so;
  so.board_height_m = o.board_height_m;
  so.bootstrap_replicates = o.bootstrap_replicates;
  so.seed = o.seed;
  so.block_s = o.block_s;
  id.senses = identify_senses(r, so);
  for (const auto& [name, iv] : id.senses.parameters) id.parameters[name] = iv;
  return id;
}

}  // namespace shelfcross::identify
