#include "flight_sw/control/control.hpp"

#include <algorithm>
#include <cmath>

#include "sdk/command.hpp"

namespace shelfcross::flight_sw {

double PiController::update(double error, double dt_s) {
  const double lim = gains_.output_limit;
  const double unsaturated = gains_.kp * error + gains_.ki * integral_;
  const bool pushing_further = (unsaturated >= lim && error > 0.0) ||
                               (unsaturated <= -lim && error < 0.0);
  if (!pushing_further) {
    integral_ = std::clamp(integral_ + error * dt_s, -gains_.integral_limit, gains_.integral_limit);
  }
  return std::clamp(gains_.kp * error + gains_.ki * integral_, -lim, lim);
}

double bang_off_bang(double psi_rad, double threshold_rad, double speed_mps) {
  if (psi_rad > threshold_rad) return speed_mps;
  if (psi_rad < -threshold_rad) return -speed_mps;
  return 0.0;
}

double height_hold_vz_mps(double target_height_m, double height_m, double kp, double speed_max_mps) {
  return std::clamp(kp * (target_height_m - height_m), -speed_max_mps, speed_max_mps);
}

std::string RcSticks::text() const { return sdk::rc_text(a, b, c, d); }

namespace {
int stick(double value) {
  return static_cast<int>(std::clamp<long>(std::lround(value), -100L, 100L));
}
}  // namespace

RcSticks to_rc(const VelocityCommand& v, const RcConversion& k) {
  return {stick(-k.rc_per_mps_horizontal * v.vy_B_mps), stick(k.rc_per_mps_horizontal * v.vx_B_mps),
          stick(k.rc_per_mps_vertical * v.vz_mps), stick(-k.rc_per_radps_yaw * v.yaw_rate_radps)};
}

RcSticks to_rc_carried(const VelocityCommand& v, const RcConversion& k, StickCarry& carry) {
  RcSticks rc = to_rc(v, k);
  const double a = -k.rc_per_mps_horizontal * v.vy_B_mps + carry.a;
  const double b = k.rc_per_mps_horizontal * v.vx_B_mps + carry.b;
  rc.a = stick(a);
  rc.b = stick(b);
  // What a saturated stick could not send is not owed later: the carry stays within a stick.
  carry.a = std::clamp(a - rc.a, -1.0, 1.0);
  carry.b = std::clamp(b - rc.b, -1.0, 1.0);
  return rc;
}

}  // namespace shelfcross::flight_sw
