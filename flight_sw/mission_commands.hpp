#pragma once
// The mission's non-rc commands ("command", "streamon", "takeoff", "land") over the SDK's
// command rules (sdk_link.hpp): each asked for with its attempts at 0, asked again on a lost or
// refused reply while timeouts.command_retries remain (the mission judges each reply: a lost
// `takeoff` reply with the drone airborne is a success), and a `land` refused in the air asked
// again after a wait rather than at once. Time is the mission's; nothing here reads a clock.

#include <optional>
#include <string>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/sdk_link.hpp"

namespace shelfcross::flight_sw {

class MissionCommands {
 public:
  using Completion = SdkLink::Completion;

  /// The gap between non-rc commands and the retries from `timeouts` (validated).
  explicit MissionCommands(const Timeouts& timeouts);

  /// Asks for a new command: it goes out by the SDK's rules (poll), its attempts from 0; a
  /// re-ask waiting (ask_again_at) is dropped.
  void ask(std::string command, double reply_timeout_s);
  /// Asks again for the command `c` completed, if retries remain: true, the attempt counted.
  bool retry(const Completion& c, double reply_timeout_s);
  /// Asks again for `command` at `at_ns` (poll sends it then), its attempts unchanged.
  void ask_again_at(std::string command, double reply_timeout_s, TimeNs at_ns);
  /// A re-ask is waiting (ask_again_at, not yet due).
  bool waiting() const { return again_.has_value(); }
  /// The waiting re-ask dropped (the mission saw the command's effect without its reply).
  void cancel_wait() { again_.reset(); }
  int attempts() const { return attempts_; }

  /// A reply: completes the outstanding command, or is stale and counted.
  std::optional<Completion> on_reply(const SdkReply& reply) { return link_.on_reply(reply); }
  /// The outstanding command, if its reply is overdue.
  std::optional<Completion> check_timeout(TimeNs now_ns) { return link_.check_timeout(now_ns); }
  /// Sends what may go now: a re-ask that is due is asked first.
  void poll(TimeNs now_ns, std::vector<SdkCommand>& out);

  bool outstanding() const { return link_.outstanding(); }
  int stale_replies() const { return link_.stale_replies(); }

 private:
  struct Again {
    std::string command;
    double reply_timeout_s = 0.0;
    TimeNs at_ns = 0;
  };
  SdkLink link_;
  int retries_ = 0;
  int attempts_ = 0;  ///< re-asks of the current command
  std::optional<Again> again_;
};

}  // namespace shelfcross::flight_sw
