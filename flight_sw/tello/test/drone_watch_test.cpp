// What the pilot loop knows of the drone, fed driver events by hand: whether a `land` was
// heard, judged by the descent the state records show after it went out.
#include "flight_sw/tello/drone_watch.hpp"

#include <gtest/gtest.h>

namespace shelfcross::tello {
namespace {

using Kind = DriverEvent::Kind;
constexpr double kAirborne_m = 0.3;

DriverEvent state_at(double t_s, double height_m) {
  DriverEvent e;
  e.t_ns = seconds_to_ns(t_s);
  e.kind = Kind::State;
  e.state = StateRecord{};
  e.state->t_ns = e.t_ns;
  e.state->height_m = height_m;
  return e;
}

DriverEvent command_event(double t_s, Kind kind, const std::string& command, const std::string& reply = "") {
  DriverEvent e;
  e.t_ns = seconds_to_ns(t_s);
  e.kind = kind;
  e.command = command;
  e.reply = reply;
  return e;
}

// Airborne at 1.2 m, a `land` sent at 10 s.
DroneWatch hovering_then_land_sent() {
  DroneWatch w(kAirborne_m);
  w.on_event(command_event(0.0, Kind::Sent, "takeoff"));
  for (double t = 5.0; t < 10.0; t += 0.1) w.on_event(state_at(t, 1.2));
  w.on_event(command_event(10.0, Kind::Sent, "land"));
  return w;
}

TEST(DroneWatch, ALandWithoutDescentIsUnheardOnlyOnceItsTimeHasPassed) {
  DroneWatch w = hovering_then_land_sent();
  const double due_s = 10.0 + DroneWatch::kLandHeard_s;
  w.on_event(state_at(due_s - 0.01, 1.21));
  EXPECT_FALSE(w.land_unheard()) << "a record before kLandHeard_s cannot tell";
  w.on_event(state_at(due_s, 1.21));
  EXPECT_TRUE(w.land_unheard()) << "hovering at its height 1.5 s after the land";
  // Sent again: the judgement starts anew from the re-send.
  w.on_event(command_event(due_s, Kind::Sent, "land"));
  w.on_event(state_at(due_s + 0.5, 1.2));
  EXPECT_FALSE(w.land_unheard());
}

TEST(DroneWatch, ALandThatTakesTheDroneDownIsHeard) {
  DroneWatch w = hovering_then_land_sent();
  // The descent a heard land gives (DroneWatch's derivation: at least 0.25 m by 1.5 s).
  w.on_event(state_at(11.5, 1.2 - 0.25));
  EXPECT_FALSE(w.land_unheard());
  // Just short of the drop the rule asks for: a hover's wander, not a landing.
  DroneWatch v = hovering_then_land_sent();
  v.on_event(state_at(11.5, 1.2 - DroneWatch::kLandHeardDrop_m + 0.01));
  EXPECT_TRUE(v.land_unheard());
}

TEST(DroneWatch, NoLandOutstandingOrDownIsNeverUnheard) {
  DroneWatch answered = hovering_then_land_sent();
  answered.on_event(command_event(11.0, Kind::Reply, "land", "error"));
  answered.on_event(state_at(12.0, 1.2));
  EXPECT_FALSE(answered.land_unheard()) << "answered: the flight software decides what next";

  DroneWatch failed = hovering_then_land_sent();
  failed.on_event(command_event(15.0, Kind::Failed, "land"));
  failed.on_event(state_at(15.5, 1.2));
  EXPECT_FALSE(failed.land_unheard());

  DroneWatch displaced = hovering_then_land_sent();
  displaced.on_event(command_event(10.5, Kind::Abandoned, "land"));
  displaced.on_event(state_at(12.0, 1.2));
  EXPECT_FALSE(displaced.land_unheard());

  DroneWatch down = hovering_then_land_sent();
  down.on_event(state_at(12.0, 0.1));
  EXPECT_FALSE(down.land_unheard()) << "on the ground";

  DroneWatch w(kAirborne_m);  // no height known when the land went out
  w.on_event(command_event(0.0, Kind::Sent, "takeoff"));
  w.on_event(command_event(10.0, Kind::Sent, "land"));
  w.on_event(state_at(12.0, 1.2));
  EXPECT_FALSE(w.land_unheard());
}

}  // namespace
}  // namespace shelfcross::tello
