#include "flight_sw/tello/calibration_manoeuvre.hpp"

#include <cmath>
#include <stdexcept>

namespace shelfcross::tello {
namespace {

constexpr double kSettle_s = 1.5;  // hover after the takeoff and between pulses: tau <= 0.7 s settles

}  // namespace

CalibrationManoeuvre::CalibrationManoeuvre(const CalibrationAmplitudes& a) {
  for (int v : {a.horizontal, a.vertical, a.yaw}) {
    if (v < 5 || v > 80) throw std::invalid_argument("calibration manoeuvre: amplitudes must be 5..80 (pulses reach 1.2 times)");
  }
  steps_.push_back({kSettle_s, {0, 0, 0, 0}, "hover"});
  // Stick index, amplitude, pulse length, pulse pairs, name.
  struct AxisPlan {
    int stick;
    int amplitude;
    double pulse_s;
    int pairs;
    const char* name;
  };
  const AxisPlan plans[] = {{1, a.horizontal, 2.0, 2, "forward"},
                            {0, a.horizontal, 2.0, 2, "right"},
                            {2, a.vertical, 1.5, 2, "up"},
                            {3, a.yaw, 2.0, 1, "clockwise"}};
  for (const AxisPlan& p : plans) {
    const int pulses = 2 * p.pairs;
    for (int j = 0; j < pulses; ++j) {
      // Amplitudes from 0.8 A to 1.2 A: the responses' plateaus then fall at different places
      // between the SDK's velocity steps (0.1 m/s), so their rounding does not bias the gain
      // the same way every time.
      const int amplitude = static_cast<int>(std::lround(p.amplitude * (0.8 + 0.4 * j / (pulses - 1))));
      const int sign = j % 2 == 0 ? 1 : -1;
      std::array<int, 4> sticks{};
      sticks[static_cast<size_t>(p.stick)] = sign * amplitude;
      steps_.push_back({p.pulse_s, sticks, std::string(p.name) + (sign > 0 ? " +" : " -") + std::to_string(amplitude)});
      steps_.push_back({kSettle_s, {0, 0, 0, 0}, "hover"});
    }
  }
}

double CalibrationManoeuvre::duration_s() const {
  double total = 0.0;
  for (const ManoeuvreStep& s : steps_) total += s.duration_s;
  return total;
}

const ManoeuvreStep* CalibrationManoeuvre::step_at(double t_s) const {
  if (t_s < 0.0) return nullptr;
  double end = 0.0;
  for (const ManoeuvreStep& s : steps_) {
    end += s.duration_s;
    if (t_s < end) return &s;
  }
  return nullptr;
}

}  // namespace shelfcross::tello
