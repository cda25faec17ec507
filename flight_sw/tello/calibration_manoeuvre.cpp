#include "flight_sw/tello/calibration_manoeuvre.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace shelfcross::tello {
namespace {

constexpr double kFirstHover_s = 1.5;  // after the takeoff
constexpr double kGap_s = 0.5;         // centred sticks after each pulse or doublet
constexpr double kLastHover_s = 1.5;   // the last response settles before the land
constexpr double kPulse_s = 2.0;       // horizontal pulses
constexpr double kHalf_s = 1.0;        // each half of a height or heading doublet
constexpr int kHorizontalPulses = 4;   // per axis
constexpr int kDoublets = 5;           // per axis
constexpr double kOverBoard_s = 8.0;   // senses block: hover over the board
constexpr double kSettle_s = 2.5;      // an axis's own edges at least this far apart (header)
constexpr double kNominalGain_mps = 1.0;  // the Tello's slow mode at full stick, nominal

// Amplitude j of n: from 0.8 A to 1.2 A, so that the responses' plateaus fall at different
// places between the SDK's velocity steps (0.1 m/s) and their rounding does not bias the gain
// the same way every time.
int ramp(int amplitude, int j, int n) { return static_cast<int>(std::lround(amplitude * (0.8 + 0.4 * j / (n - 1)))); }

std::array<int, 4> stick(int index, int value) {
  std::array<int, 4> s{};
  s[static_cast<size_t>(index)] = value;
  return s;
}

std::string signed_text(int v) {
  char text[16];
  std::snprintf(text, sizeof text, "%+d", v);
  return text;
}

}  // namespace

CalibrationManoeuvre::CalibrationManoeuvre(const CalibrationAmplitudes& a, const std::optional<CalibrationSenses>& senses) {
  for (int v : {a.horizontal, a.vertical, a.yaw}) {
    if (v < 5 || v > 80) throw std::invalid_argument("calibration manoeuvre: amplitudes must be 5..80 (pulses reach 1.2 times)");
  }
  if (senses && !(senses->board_distance_m >= kBoardDistanceMin_m && senses->board_distance_m <= kBoardDistanceMax_m)) {
    throw std::invalid_argument("calibration manoeuvre: the board's distance must be 1.0..2.5 m");
  }
  const std::array<int, 4> centred{};
  steps_.push_back({kFirstHover_s, centred, "hover"});
  if (senses) {
    // Out and back at the same stick for the same time: the drone ends where it began.
    const double pass_s = senses->board_distance_m / (kNominalGain_mps * kPassStick / 100.0);
    steps_.push_back({kStillHover_s, centred, "hover still"});
    steps_.push_back({pass_s, stick(1, -kPassStick), "back to the board " + signed_text(-kPassStick)});
    steps_.push_back({kOverBoard_s, centred, "hover over the board"});
    steps_.push_back({pass_s, stick(1, kPassStick), "forward from the board " + signed_text(kPassStick)});
    steps_.push_back({kSettle_s, centred, "hover"});
  }
  // Horizontal: forward (stick b), then right (stick a), the same amplitude and sign, then the
  // next amplitude with the other sign: each axis ends near where it began.
  for (int j = 0; j < kHorizontalPulses; ++j) {
    const int v = (j % 2 == 0 ? 1 : -1) * ramp(a.horizontal, j, kHorizontalPulses);
    steps_.push_back({kPulse_s, stick(1, v), "forward " + signed_text(v)});
    steps_.push_back({kGap_s, centred, "hover"});
    steps_.push_back({kPulse_s, stick(0, v), "right " + signed_text(v)});
    steps_.push_back({kGap_s, centred, "hover"});
  }
  // Height (stick c) and heading (stick d) doublets in turn.
  for (int j = 0; j < kDoublets; ++j) {
    const int up = ramp(a.vertical, j, kDoublets);
    steps_.push_back({kHalf_s, stick(2, up), "up " + signed_text(up)});
    steps_.push_back({kHalf_s, stick(2, -up), "up " + signed_text(-up)});
    steps_.push_back({kGap_s, centred, "hover"});
    const int cw = (j % 2 == 0 ? 1 : -1) * ramp(a.yaw, j, kDoublets);
    steps_.push_back({kHalf_s, stick(3, cw), "clockwise " + signed_text(cw)});
    steps_.push_back({kHalf_s, stick(3, -cw), "clockwise " + signed_text(-cw)});
    steps_.push_back({kGap_s, centred, "hover"});
  }
  steps_.back().duration_s = kLastHover_s;
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
