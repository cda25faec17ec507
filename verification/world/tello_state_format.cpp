#include "verification/world/tello_state_format.hpp"

#include <cmath>
#include <cstdio>

#include "sdk/state_record.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::verification {

std::string format_state_record(const StateRecord& s) {
  const auto i = [](double v) { return static_cast<long>(std::lround(v)); };
  const long tof_cm = s.tof_m ? i(*s.tof_m * 100.0) : sdk::kTofInvalid_cm;
  char text[512];
  std::snprintf(text, sizeof(text),
                "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:%ld;roll:%ld;yaw:%ld;vgx:%ld;vgy:%ld;vgz:%ld;"
                "templ:%ld;temph:%ld;tof:%ld;h:%ld;bat:%d;baro:%.2f;time:%ld;agx:%.2f;agy:%.2f;agz:%.2f;\r\n",
                i(rad_to_deg(-s.pitch_rad)), i(rad_to_deg(s.roll_rad)), i(rad_to_deg(-s.yaw_rad)),
                i(s.vx_H_mps * 10.0), i(-s.vy_H_mps * 10.0), i(-s.vz_H_mps * 10.0), i(s.temp_low_c),
                i(s.temp_high_c), tof_cm, i(s.height_m * 100.0), s.battery_pct, s.baro_m.value_or(0.0),
                i(std::floor(s.motor_time_s)), s.ax_B_mps2 / sdk::kStandardGravity_mps2 * 1e3,
                -s.ay_B_mps2 / sdk::kStandardGravity_mps2 * 1e3, -s.az_B_mps2 / sdk::kStandardGravity_mps2 * 1e3);
  return text;
}

}  // namespace shelfcross::verification
