#pragma once
// The link's outages in the air, as the pilot loop rides through them (pilot_loop.hpp).
//
// A Wi-Fi re-association silences every channel, both ways, for seconds. Nothing the program
// sends reaches the drone meanwhile: the Tello flies the last sticks it heard until it hears
// others (in a crossing, the forward stick flies on, blind, toward the next shelf) and lands by
// itself sdk::kCommandWatchdog_s after the last command it heard (docs/tello_sdk.md). A `land` sent in the
// silence waits for the link like every other datagram, so landing at the first seconds of
// silence gains nothing in the air and loses the mission to every outage longer than that.
//
// So: with no state record for `lost_after_s` (Failsafes::state_timeout_s) the link is out, and
// the program hovers (rc 0 0 0 0, the flight software's sticks withheld): the first datagram
// through when the link returns stops the drone. When a state record comes, the link is back and
// control returns to the flight software, which re-acquires from the pictures (the video's stall
// timers, its and the program's, run from the link's return). Only with no state record for
// `give_up_after_s` (Failsafes::link_outage_s) does the program give up and land.
//
// The bound follows from the Tello. The driver sends a command at least every keep-alive period
// (DriverConfig::keepalive_ns, 5 s; the rc stream every 0.1 s while the sticks are live), so the
// last command the drone heard may be that old when the link went, and its watchdog may land it
// kCommandWatchdog_s - keep-alive = 10 s after the last state record. Past that, a mission resumed
// might find the drone descending on its own wherever it is: longest_outage_s().

#include <optional>

#include "flight_sw/tello/clock.hpp"
#include "sdk/command.hpp"

namespace shelfcross::tello {

/// What the link's watch says on a pass of the loop, airborne (LinkWatch::check).
enum class LinkVerdict {
  Live,    ///< state records arrive
  Back,    ///< the first pass after the link came back: control returns to the flight software
  Lost,    ///< the first pass with the link out: hover from now on
  Out,     ///< still out, within the bound: hover
  GiveUp,  ///< out longer than the bound: land
};

class LinkWatch {
 public:
  /// The longest a ride through may last: the Tello's watchdog less the driver's keep-alive period.
  static double longest_outage_s(double keepalive_s) { return sdk::kCommandWatchdog_s - keepalive_s; }

  /// lost_after_s <= give_up_after_s, both positive (the pilot file's checks).
  LinkWatch(double lost_after_s, double give_up_after_s)
      : lost_after_ns_(seconds_to_ns(lost_after_s)), give_up_after_ns_(seconds_to_ns(give_up_after_s)) {}

  /// The verdict at now_ns, airborne, the newest state record received at last_state_ns.
  LinkVerdict check(TimeNs now_ns, TimeNs last_state_ns);
  /// The link is out (since a Lost verdict, until the next Back).
  bool out() const { return out_since_ns_.has_value(); }
  /// The newest state record when the link went out (valid while out()).
  TimeNs out_since_ns() const { return out_since_ns_.value_or(0); }
  /// When the link last came back (the first state record after an outage); none before one.
  std::optional<TimeNs> back_ns() const { return back_ns_; }
  /// How long the last outage lasted, from its last state record to the first after it.
  double last_outage_s() const { return last_outage_s_; }

 private:
  TimeNs lost_after_ns_;
  TimeNs give_up_after_ns_;
  std::optional<TimeNs> out_since_ns_;  ///< the last state record before the outage
  std::optional<TimeNs> back_ns_;
  double last_outage_s_ = 0.0;
};

}  // namespace shelfcross::tello
