#pragma once
// How strongly the Tello answers its sticks, measured in flight (docs/method.md section 8).
//
// The loops of the approach (eq. 12, eq. 15, the lateral law) and the open-loop crossing are
// tuned for an autopilot that turns a stick of rc_per_mps into 1 m/s; one that answers twice
// as strongly doubles every loop's gain, and with a slow velocity hold the vertical and heading
// loops overshoot until the target's tags leave the picture. So the flight software compares
// what it asked with what the state record shows and, once the answer is shown to be stronger
// than the loops were certified for, scales its sticks down by it.
//
// Model, per axis (horizontal: the body's x and y pooled; vertical; yaw): the autopilot holds
// a first-order response to the stick's rate u (the stick over the nominal rc_per_* of
// RcConversion) after a dead time T, v'(t) = (k u(t - T) - v(t)) / tau, k the gain sought. Over
// a window of length W the vehicle moves D = k C + e, C the integral of u delayed by T and
// passed through the lag, e what the model's error and the air add. For each trial (T, tau),
// five dead times by sixteen lags, the least squares k = S_dc / S_cc over every window (one
// ending at each state record) and its residual are kept; the trial with the least residual
// gives the estimate. The dead time matters because the loops close through the vehicle: the
// heading law's stick shrinks as the heading closes in, so a response to an older (larger)
// stick, fitted without its dead time, reads as a stronger gain (a Tello at 1.2 with 0.1 s of
// dead time and a 0.3 s yaw lag, flown by the heading law, read 1.27). D: the state's
// heading-frame velocities summed over the records (0.1 m/s steps), the height's change (1 cm
// steps), the yaw's change (1 degree steps); W = 1 s, long against those steps (0.05 m,
// 0.01 m, 0.017 rad of the few tenths a window moves). Only windows during which rc datagrams went out throughout count: during take-off
// and landing the Tello moves on its own.
#include <array>
#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

enum class StickAxis { Horizontal = 0, Vertical = 1, Yaw = 2 };
inline constexpr int kStickAxes = 3;

/// "horizontal", "vertical", "yaw": the axis's name in events and stored metrics.
const char* stick_axis_name(StickAxis axis);

/// One axis's estimate: the gain k (the answer over the nominal one), its standard error, the
/// lag tau and dead time of the best fit and the windows it rests on; and the scale the
/// axis's sticks are sent at since it.
struct AxisResponse {
  double gain = 1.0;
  double gain_se = 0.0;
  double tau_s = 0.0;
  double delay_s = 0.0;
  int windows = 0;
  double scale = 1.0;
};

/// Each axis's estimate, per StickAxis; empty until measured.
using StickEstimates = std::array<std::optional<AxisResponse>, kStickAxes>;

/// The fit's trials: sixteen lags by five dead times (stick_response.cpp, kTrialTau_s and
/// kTrialDelay_s).
inline constexpr int kStickTrialLags = 16;
inline constexpr int kStickTrialDelays = 5;

class StickResponse {
 public:
  explicit StickResponse(const RcConversion& nominal) : nominal_(nominal) {}

  /// The sticks sent at t_ns (held by the Tello until the next).
  void on_sent(const RcSticks& rc, TimeNs t_ns);
  /// A state record: a window ends here.
  void on_state(const StateRecord& s);

  /// The axis's estimate as of the last state record, once enough windows were driven
  /// (stick_response.cpp, kMinWindows).
  const std::optional<AxisResponse>& estimate(StickAxis axis) const { return axes_[static_cast<int>(axis)].estimate; }
  /// Every axis's estimate.
  StickEstimates estimates() const;
  /// The factor the axis's sticks are scaled by: 1 / k once k - 2 se has exceeded what the
  /// certified envelope holds on the axis over kConfirmWindows windows (k capped;
  /// stick_response.cpp), else 1. Once engaged it stays engaged (the factor follows the
  /// estimate, at most 1).
  double scale(StickAxis axis) const { return axes_[static_cast<int>(axis)].scale; }
  /// The conversion the sticks are sent with: the nominal one times each axis's scale.
  RcConversion conversion() const;
  /// Set when an axis's scaling engaged on the last on_state (cleared by the next).
  std::optional<StickAxis> engaged() const { return engaged_; }

 private:
  /// Components: x, y (horizontal pooled), z, yaw.
  static constexpr int kComp = 4;
  static constexpr int kTrials = kStickTrialLags * kStickTrialDelays;
  struct Sums {
    double dc = 0.0, cc = 0.0, dd = 0.0;
  };
  /// One axis's sums over its windows, and what they gave.
  struct Axis {
    std::array<Sums, kTrials> sums{};
    int windows = 0;
    /// The windows at which k - 2 se last rose past the axis's bar (and has stayed past it).
    std::optional<int> above_since;
    double scale = 1.0;
    std::optional<AxisResponse> estimate;  ///< fit() with the scale, each record
  };
  using Rates = std::array<double, kComp>;
  struct Sample {
    TimeNs t_ns = 0;
    Rates moved{};                       ///< measured displacement since start
    std::array<Rates, kTrials> cmd{};  ///< the delayed, lagged command's integral per trial
  };
  /// Integrates every trial's delayed, lagged command up to t_ns.
  void advance(TimeNs t_ns);
  /// Integrates the trials of dead time `delay` over [from_ns, to_ns) with the rates u held.
  void integrate(int delay, const Rates& u, TimeNs from_ns, TimeNs to_ns);
  /// The least-squares fit of axis `ax` over the windows so far (its scale left at 1).
  std::optional<AxisResponse> fit(int ax) const;
  static int axis_of(int comp) { return comp < 2 ? 0 : comp - 1; }

  RcConversion nominal_;
  /// The sticks' rates as sent, from the last one every dead time still holds.
  std::deque<std::pair<TimeNs, Rates>> sent_;
  std::array<Rates, kTrials> u_lag_{};  ///< each trial lag's output
  Sample now_;                          ///< integrals up to now_.t_ns
  std::optional<TimeNs> last_sent_ns_;
  std::optional<StateRecord> last_state_;
  std::deque<Sample> samples_;  ///< at the state records of the last window
  std::array<Axis, kStickAxes> axes_{};
  std::optional<StickAxis> engaged_;
};

/// The event that says an axis's scaling engaged: the gain, its lag and the scale.
std::string stick_scaling_event(StickAxis axis, const StickResponse& response);

/// What was measured of each axis (Telemetry's control.sticks), for a flight's summary:
/// "horizontal 1.03 (+-0.02, lag 0.40 s after 0.05 s, 312 windows) sent at 1.00; vertical
/// ...; yaw not measured".
std::string stick_response_text(const StickEstimates& sticks);

}  // namespace shelfcross::flight_sw
