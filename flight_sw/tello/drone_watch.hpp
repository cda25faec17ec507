#pragma once
// What the pilot loop knows of the drone, from the driver's events and the frames it takes
// (pilot_loop.hpp): the newest state record (its time, battery and height), the newest frame,
// whether the drone is airborne ("airborne" = a takeoff was sent and no land has been
// acknowledged since), and whether the last `land` sent is being acted on. Its failsafes
// decide on these.

#include <optional>

#include "flight_sw/tello/sdk_driver.hpp"

namespace shelfcross::tello {

/// True for a Reply event whose reply is "ok".
bool accepted(const DriverEvent& e);

class DroneWatch {
 public:
  /// How long after a `land` datagram the height must have fallen, and by how much, for the
  /// drone to have heard it. The Tello answers a `land` only once down (about 2 s from 1 m),
  /// so its reply cannot tell early that the datagram was lost; its descent can. At the
  /// firmware's 0.5 m/s, with a vertical time constant up to 1.2 s (the widest drawn beyond
  /// the envelope; 0.4 s certified) and 0.2 s of command and state latency, a heard `land`
  /// has taken the drone down by 0.5 (1.3 - 1.2 (1 - e^(-1.3/1.2))) = 0.25 m after 1.5 s; a
  /// hovering drone holds its height within a few centimetres.
  static constexpr double kLandHeard_s = 1.5;
  static constexpr double kLandHeardDrop_m = 0.10;

  /// airborne_height_m: at or below this height the drone is on the ground (the flight
  /// software's own mission.airborne_height_m, so that the two agree on "down").
  explicit DroneWatch(double airborne_height_m) : airborne_height_m_(airborne_height_m) {}

  /// Follows a driver event: a state record; a takeoff sent (airborne from then); the reply
  /// to a land, or its failure (down when accepted or the height says so); a refused takeoff
  /// (still down unless the height says otherwise).
  void on_event(const DriverEvent& e);
  /// A frame handed over at handed_ns.
  void on_frame(TimeNs handed_ns) { last_frame_ns_ = handed_ns; }
  /// The flight software found the drone down (its land reply lost): agreed when the newest
  /// height says so too.
  void landed_if_grounded() {
    if (airborne_ && grounded()) airborne_ = false;
  }

  /// A `land` is outstanding (sent, neither answered nor failed), the drone is not down, and a
  /// state record received kLandHeard_s or more after the last send of it puts the drone
  /// within kLandHeardDrop_m of its height then: the datagram was lost; send it again.
  bool land_unheard() const;

  bool airborne() const { return airborne_; }
  TimeNs airborne_since_ns() const { return airborne_since_ns_; }
  /// The newest state record puts the drone at or below the airborne height.
  bool grounded() const { return last_height_m_ && *last_height_m_ <= airborne_height_m_; }
  std::optional<TimeNs> last_state_ns() const { return last_state_ns_; }
  std::optional<TimeNs> last_frame_ns() const { return last_frame_ns_; }
  int battery_pct() const { return battery_pct_; }  ///< -1 before the first state record

 private:
  double airborne_height_m_;
  std::optional<TimeNs> last_state_ns_;
  std::optional<TimeNs> last_frame_ns_;
  int battery_pct_ = -1;
  std::optional<double> last_height_m_;
  bool airborne_ = false;
  TimeNs airborne_since_ns_ = 0;
  struct LandSent {
    TimeNs t_ns = 0;                 ///< the last send (first or re-send)
    std::optional<double> height_m;  ///< the newest height then
  };
  std::optional<LandSent> land_sent_;  ///< while a `land` is outstanding
};

}  // namespace shelfcross::tello
