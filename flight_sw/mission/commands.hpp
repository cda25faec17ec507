#pragma once
// The mission's non-rc commands ("command", "streamon", "takeoff", "land") over the Tello SDK's
// command rules (docs/tello_sdk.md), which CommandPacer keeps (command_pacer.hpp: one non-rc
// command outstanding, the gap between sends, the reply timeout). What is the mission's own:
// the one command waiting to go (a newer one replaces it), each asked for with its attempts
// at 0 and asked again on a lost or refused reply while timeouts.command_retries remain (the
// mission judges each reply: a lost `takeoff` reply with the drone airborne is a success), a
// `land` refused in the air asked again after a wait rather than at once, and the replies
// that answer nothing (stale) dropped and counted. rc commands need no reply and go out at
// once, not through here. Time is the stamp of the input being handled; nothing here reads a
// clock.

#include <optional>
#include <string>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/command_pacer.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

class MissionCommands {
 public:
  /// How a non-rc command ended.
  struct Completion {
    std::string command;
    std::string reply;  ///< reply text ("" on timeout)
    bool ok = false;    ///< the reply was "ok" (is_ok_reply: any case, surrounding blanks ignored)
    bool timed_out = false;
  };

  /// The gap between non-rc commands and the retries from `timeouts`. Requires them
  /// validated (config.cpp: command_gap_s >= 0, command_retries >= 0); nothing is checked here.
  explicit MissionCommands(const Timeouts& timeouts);

  /// Asks for a new command, its attempts from 0: it waits to go out by the SDK's rules
  /// (poll), replacing a command waiting that has not gone yet; a re-ask waiting
  /// (ask_again_at) is dropped. A command outstanding stays so until its reply or timeout.
  void ask(std::string command, double reply_timeout_s);
  /// Asks again for `command` (the one that just completed) if retries remain: true, the
  /// attempt counted (attempts()); false, nothing asked, when the retries are spent.
  bool retry(const std::string& command, double reply_timeout_s);
  /// Asks again for `command` at `at_ns` (poll asks for it then, as `ask` would but with its
  /// attempts unchanged). Replaces a re-ask already waiting.
  void ask_again_at(std::string command, double reply_timeout_s, TimeNs at_ns);
  /// A re-ask is waiting (ask_again_at, not yet taken by poll).
  bool waiting() const { return again_.has_value(); }
  /// The waiting re-ask dropped (the mission saw the command's effect without its reply);
  /// nothing when none waits.
  void cancel_wait() { again_.reset(); }
  /// Re-asks (retry) of the command last asked for.
  int attempts() const { return attempts_; }

  /// A reply: completes the outstanding command; with none outstanding it is stale, dropped
  /// and counted (stale_replies), and nothing is returned.
  std::optional<Completion> on_reply(const SdkReply& reply);
  /// The outstanding command, completed as timed out, if its reply is overdue at now_ns;
  /// otherwise (none outstanding, or not yet due) nothing.
  std::optional<Completion> check_timeout(TimeNs now_ns);
  /// Sends what may go at now_ns, appending it to `out`: a re-ask that is due is asked for
  /// first; the waiting command goes once none is outstanding and the gap since the last
  /// send has passed.
  void poll(TimeNs now_ns, std::vector<SdkCommand>& out);

  bool outstanding() const { return pacer_.outstanding() != nullptr; }
  int stale_replies() const { return stale_replies_; }

 private:
  struct Waiting {  ///< the command waiting to go out by the SDK's rules
    std::string text;
    TimeNs timeout_ns = 0;
  };
  struct Again {  ///< a re-ask waiting for its time
    std::string command;
    double reply_timeout_s = 0.0;
    TimeNs at_ns = 0;
  };
  /// The command waiting to go becomes `text` (replacing any), its reply due within
  /// reply_timeout_s of its send.
  void queue(std::string text, double reply_timeout_s);

  CommandPacer<std::string> pacer_;  ///< the outstanding command's text; the gap, the timeout
  std::optional<Waiting> queued_;
  std::optional<Again> again_;
  int retries_ = 0;
  int attempts_ = 0;  ///< re-asks of the current command
  int stale_replies_ = 0;
};

}  // namespace shelfcross::flight_sw
