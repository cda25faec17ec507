#include "flight_sw/mission/phases.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace shelfcross::flight_sw {

const char* phase_name(Phase p) {
  switch (p) {
    case Phase::Idle: return "idle";
    case Phase::EnterSdk: return "enter_sdk";
    case Phase::StartVideo: return "start_video";
    case Phase::WaitVideo: return "wait_video";
    case Phase::TakeOff: return "take_off";
    case Phase::FindShelf: return "find_shelf";
    case Phase::GoToViewpoint: return "go_to_viewpoint";
    case Phase::TakeInventory: return "take_inventory";
    case Phase::Approach: return "approach";
    case Phase::Cross: return "cross";
    case Phase::Transfer: return "transfer";
    case Phase::Land: return "land";
    case Phase::Done: return "done";
  }
  return "?";
}

namespace {

constexpr std::size_t kPhases = static_cast<std::size_t>(Phase::Done) + 1;
using Targets = std::uint32_t;  // bit p: Phase p may be entered

constexpr Targets bits(std::initializer_list<Phase> phases) {
  Targets t = 0;
  for (Phase p : phases) t |= Targets{1} << static_cast<unsigned>(p);
  return t;
}

// The transitions, each with the event that takes it. Every airborne phase may also Land
// (its timeout, low battery, video lost); the ground phases end in Done when a command fails.
constexpr std::array<Targets, kPhases> kNext = [] {
  std::array<Targets, kPhases> t{};
  auto at = [&](Phase p) -> Targets& { return t[static_cast<std::size_t>(p)]; };
  at(Phase::Idle) = bits({Phase::EnterSdk});                         // start()
  at(Phase::EnterSdk) = bits({Phase::StartVideo, Phase::Done});      // "command" ok / failed
  at(Phase::StartVideo) = bits({Phase::WaitVideo, Phase::Done});     // "streamon" ok / failed
  at(Phase::WaitVideo) = bits({Phase::TakeOff, Phase::Done});        // first frame / no video, battery low
  at(Phase::TakeOff) = bits({Phase::FindShelf, Phase::Done});        // airborne / takeoff failed
  at(Phase::FindShelf) = bits({Phase::GoToViewpoint, Phase::Land});  // whole grid in view
  at(Phase::GoToViewpoint) =                                         // at the viewpoint, settled /
      bits({Phase::TakeInventory, Phase::FindShelf, Phase::Land});   // shelf out of view
  at(Phase::TakeInventory) =                                         // target chosen / conventional
      bits({Phase::Approach, Phase::Transfer, Phase::FindShelf,      // strategy / shelf out of
            Phase::Land});                                           // view / no empty cell
  at(Phase::Approach) =                                              // gate clear / target in
      bits({Phase::Cross, Phase::FindShelf, Phase::Land});           // doubt: re-read / given up
  at(Phase::Cross) =                                                 // next shelf / drift seen
      bits({Phase::FindShelf, Phase::Approach, Phase::Land});        // before the cell / crossed
  at(Phase::Transfer) = bits({Phase::FindShelf, Phase::Land});       // next shelf / past the last
  at(Phase::Land) = bits({Phase::Done});                             // down (or not acknowledged)
  at(Phase::Done) = 0;
  return t;
}();

}  // namespace

bool may_enter(Phase from, Phase to) {
  return (kNext[static_cast<std::size_t>(from)] >> static_cast<unsigned>(to)) & 1u;
}

bool airborne(Phase p) {
  return p == Phase::FindShelf || p == Phase::GoToViewpoint || p == Phase::TakeInventory ||
         p == Phase::Approach || p == Phase::Cross || p == Phase::Transfer;
}

bool vision_phase(Phase p) { return airborne(p) && p != Phase::Cross && p != Phase::Transfer; }

void PhaseClock::enter(Phase to, TimeNs now_ns) {
  if (!may_enter(phase_, to)) {
    throw std::logic_error(std::string("mission: no transition from ") + phase_name(phase_) + " to " + phase_name(to));
  }
  phase_ = to;
  start_ns_ = now_ns;
}

}  // namespace shelfcross::flight_sw
