#include "flight_sw/tello/drone_watch.hpp"

#include "flight_sw/mission/command_pacer.hpp"

namespace shelfcross::tello {

bool accepted(const DriverEvent& e) { return e.kind == DriverEvent::Kind::Reply && flight_sw::is_ok_reply(e.reply); }

void DroneWatch::on_event(const DriverEvent& e) {
  using K = DriverEvent::Kind;
  if (e.kind == K::State && e.state) {
    last_state_ns_ = e.t_ns;
    battery_pct_ = e.state->battery_pct;
    last_height_m_ = e.state->height_m;
  } else if (e.kind == K::Sent && e.command == "takeoff") {
    if (!airborne_) airborne_since_ns_ = e.t_ns;
    airborne_ = true;
  } else if (e.kind == K::Sent && e.command == "land") {
    land_sent_ = LandSent{e.t_ns, last_height_m_};
  } else if (e.kind == K::Abandoned && e.command == "land") {
    land_sent_.reset();
  } else if (e.kind == K::Reply || e.kind == K::Failed) {
    if (e.command == "land") land_sent_.reset();
    const bool ok = accepted(e);
    // A `land` whose `ok` was lost: repeated, it finds the drone on the ground and gets
    // `error`, or times out; the state height says whether it is down.
    if (e.command == "land" && (ok || grounded())) airborne_ = false;
    // A refused takeoff ("error No valid imu", ...) left the drone on the ground, unless
    // the state stream says otherwise.
    if (e.command == "takeoff" && e.kind == K::Reply && !ok &&
        !(last_height_m_ && *last_height_m_ > airborne_height_m_)) {
      airborne_ = false;
    }
  }
}

bool DroneWatch::land_unheard() const {
  if (!land_sent_ || !land_sent_->height_m || !last_state_ns_ || !last_height_m_ || grounded()) return false;
  return *last_state_ns_ - land_sent_->t_ns >= seconds_to_ns(kLandHeard_s) &&
         *last_height_m_ > *land_sent_->height_m - kLandHeardDrop_m;
}

}  // namespace shelfcross::tello
