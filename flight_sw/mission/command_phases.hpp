#pragma once
// The phases the SDK's non-rc commands carry (flight_software.hpp): EnterSdk ("command"),
// StartVideo ("streamon"), WaitVideo's take-off on the first picture, TakeOff ("takeoff") and
// Land ("land"), and the mission's result. Each command's reply, or its loss, is judged here
// (MissionCommands keeps the SDK's rules, the retries and the re-asks): a lost `takeoff` reply
// with the state height airborne is a success, a lost `land` `ok` with it down too, a `land`
// refused in the air is asked again after a wait, a `takeoff` refused on every attempt ends on
// the ground only once the state height shows no takeoff under way. Each step returns the
// transition it decided, which the mission takes (FlightSoftware::enter), and calls nothing
// back.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/commands.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/mission.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

class CommandPhases {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit CommandPhases(const FlightConfig& config) : config_(config), commands_(config.timeouts) {}

  /// The entered phase's command, asked for anew (MissionCommands::ask).
  void ask(std::string command, double reply_timeout_s) { commands_.ask(std::move(command), reply_timeout_s); }
  /// A reply while the mission runs: the command it completes judged, the transition that
  /// calls for returned; a stale one dropped and counted.
  std::optional<Transition> on_reply(const SdkReply& reply, MissionFacts& facts);
  /// A reply before the start or after the end: it completes the outstanding command unjudged,
  /// or is counted stale.
  void drain(const SdkReply& reply) { commands_.on_reply(reply); }
  /// The outstanding command, its reply overdue, judged as lost (the transition that calls for
  /// returned); nothing otherwise.
  std::optional<Transition> check_timeout(MissionFacts& facts);
  /// Sends what may go now (MissionCommands::poll), appended to `out`.
  void poll(TimeNs now_ns, std::vector<SdkCommand>& out) { commands_.poll(now_ns, out); }
  bool outstanding() const { return commands_.outstanding(); }
  int stale_replies() const { return commands_.stale_replies(); }

  /// WaitVideo's first picture proves the video: TakeOff, unless the last state record's
  /// battery is below mission.takeoff_min_battery_pct (then Done: the mission ends on the ground).
  Transition take_off_if_ready(const MissionFacts& facts);
  /// The timers of the phases on the ground and of Land (call in every phase not airborne):
  /// no video timeouts.video_start_s after streamon ends the mission on the ground; in
  /// TakeOff, after every `takeoff` was refused, a fresh state record up and vertically still
  /// says airborne, and the height still low after a wait says on the ground; in Land, after
  /// a refused `land`, a fresh state record low and vertically still says down. Returns the
  /// transition that decides.
  std::optional<Transition> supervise(const MissionFacts& facts);
  /// The mission lands: once down it ends in `outcome`, `reason` the result's reason.
  void landing(Outcome outcome, const std::string& reason);
  const MissionResult& result() const { return result_; }

 private:
  std::optional<Transition> on_completion(const MissionCommands::Completion& c, MissionFacts& facts);
  /// Ends the Land phase (Done) with the pending outcome; `landed` false: not acknowledged.
  Transition finish_landing(bool landed, const std::string& why);
  /// The Land phase has lasted longer than a landing may take (timeouts.land_reply_s).
  bool land_given_up(const MissionFacts& facts) const;
  /// Ends the mission on the ground (Done), aborted with `reason`.
  Transition abort_on_ground(const std::string& reason);

  struct TakeoffRefused {  ///< every `takeoff` refused: the last refusal, and when it came
    std::string reply;
    TimeNs since_ns = 0;
  };

  const FlightConfig& config_;
  MissionCommands commands_;  ///< the non-rc commands, their retries and re-asks
  MissionResult result_;
  Outcome pending_outcome_ = Outcome::Aborted;  ///< the outcome a Land phase ends in
  std::optional<TakeoffRefused> takeoff_refused_;  ///< set: TakeOff watches the state height
};

}  // namespace shelfcross::flight_sw
