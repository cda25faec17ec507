#pragma once
// The driver's stick input (sdk_driver.hpp): rc gets no reply and is never waited for. The
// latest setpoint goes out at once (rc_new_copies times, rc_min_gap_ns apart) and is repeated
// every rc_period_ns while it is fresh (set within rc_hold_ns); one not renewed for rc_hold_ns
// falls back to "rc 0 0 0 0" (hover). After deflected sticks went out, a manoeuvre waits for
// centred ones (stop_rc_repeats). The repeater decides; the driver sends. It reads no clock.

#include <optional>
#include <string>

#include "flight_sw/tello/sdk_driver_types.hpp"

namespace shelfcross::tello {

/// Centred sticks: hover.
inline constexpr const char* kHoverRc = "rc 0 0 0 0";

class RcRepeater {
 public:
  /// Keeps a reference to `config`: it must outlive the repeater.
  explicit RcRepeater(const DriverConfig& config) : config_(config) {}

  /// The sticks `text` (an rc command) set at now. New sticks go out rc_new_copies times;
  /// the same sticks again only renew the setpoint (the steady repeat sends them).
  void set(const std::string& text, TimeNs now);
  /// No stick input any more (a manoeuvre, an urgent command): nothing is repeated.
  void clear() { setpoint_.reset(); }
  /// The rc due at now, or nothing: a copy of new sticks, or the steady repeat while the
  /// setpoint is fresh; a setpoint not renewed for rc_hold_ns becomes hover (new sticks).
  /// Nothing while rc_min_gap_ns has not passed since the last rc.
  std::optional<std::string> due(TimeNs now);
  /// True when rc_min_gap_ns has passed since the last rc (or none went out yet).
  bool gap_passed(TimeNs now) const;
  /// True when centred sticks must go out before a manoeuvre.
  bool stops_owed() const { return stops_owed_ > 0; }
  /// An rc was handed to the wire at now (sent or not).
  void attempted(TimeNs now) { last_rc_ns_ = now; }
  /// An rc went out: centred sticks pay one stop owed, deflected ones owe stop_rc_repeats.
  void went_out(const std::string& text);

 private:
  const DriverConfig& config_;
  std::optional<std::string> setpoint_;
  TimeNs set_ns_ = 0;
  int new_owed_ = 0;  ///< copies of new sticks still to send (rc_new_copies)
  std::optional<TimeNs> last_rc_ns_;
  int stops_owed_ = 0;  ///< "rc 0 0 0 0" still to send before a manoeuvre
};

}  // namespace shelfcross::tello
