#include "flight_sw/control/sticks.hpp"

#include <algorithm>

namespace shelfcross::flight_sw {

Sticks::Sticks(const FlightConfig& config)
    : gains_(config.control),
      rc_(config.rc),
      response_(config.rc),
      pi_z_({config.control.kp_z, config.control.ki_z, config.control.z_integral_limit_m_s,
             config.control.z_speed_max_mps}),
      pi_psi_({config.control.kp_psi, config.control.ki_psi, config.control.psi_integral_limit_rad_s,
               config.control.yaw_rate_max_radps}) {}

void Sticks::set(const VelocityCommand& v, TimeNs now_ns) {
  velocity_ = v;
  set_ns_ = now_ns;
  carry_.reset();
}

void Sticks::fly_line(const VelocityCommand& v, TimeNs now_ns) {
  set(v, now_ns);
  carry_.emplace();
}

void Sticks::hover() {
  velocity_ = {};
  carry_.reset();
  restart_loops();
}

void Sticks::restart_loops() {
  pi_z_.reset();
  pi_psi_.reset();
}

// Snapping to hover on every picture that cannot steer starts and stops the vehicle with the
// link's loss: each 0.25 m/s step tips the Tello by a few degrees, and its camera, fixed to the
// body, swings the shelf by fy * 4 deg ~ 65 px up and down the picture, off the tracker's
// search window (corner_gate 0.35 of a 160 px box is 57 px), so that the target is lost on the
// very pictures that could have measured it. Holding the last command over a short gap keeps
// the vehicle steady instead.
void Sticks::hold_or_hover(TimeNs now_ns, bool leaving) {
  if (leaving || !set_ns_ || ns_to_seconds(now_ns - *set_ns_) > gains_.unsteered_hold_s) {
    velocity_ = {};
    carry_.reset();
  }
}

VelocityCommand Sticks::steer(double e_z_m, double e_psi_rad, double dt_s) {
  VelocityCommand v;
  v.vz_mps = pi_z_.update(e_z_m, dt_s);
  v.yaw_rate_radps = pi_psi_.update(e_psi_rad, dt_s);
  return v;
}

double Sticks::control_dt_s(TimeNs now_ns) const {
  if (!last_control_ns_) return 0.0;
  return std::min(ns_to_seconds(now_ns - *last_control_ns_), gains_.max_control_dt_s);
}

std::optional<RcSticks> Sticks::due(TimeNs now_ns, bool force) {
  if (!force && last_rc_ns_ && ns_to_seconds(now_ns - *last_rc_ns_) < rc_.rc_period_s) return std::nullopt;
  last_rc_ns_ = now_ns;
  const RcConversion k = response_.conversion();
  const RcSticks rc = carry_ ? to_rc_carried(velocity_, k, *carry_) : to_rc(velocity_, k);
  response_.on_sent(rc, now_ns);
  return rc;
}

bool Sticks::keepalive_due(TimeNs now_ns) const {
  return !last_rc_ns_ || ns_to_seconds(now_ns - *last_rc_ns_) >= rc_.keepalive_s;
}

}  // namespace shelfcross::flight_sw
