#pragma once
// The flight software's side of the Tello SDK's command rules (docs/tello_sdk.md): the rules
// themselves (one non-rc command outstanding, the gap, the reply timeout) are CommandPacer's
// (command_pacer.hpp); this link holds the one command waiting to go and says how each ended.
// rc commands need no reply and go out at once, not through here. Time is the stamp of the
// input being handled; nothing here reads a clock.

#include <optional>
#include <string>
#include <vector>

#include "flight_sw/command_pacer.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

class SdkLink {
 public:
  /// How a non-rc command ended.
  struct Completion {
    std::string command;
    std::string reply;       ///< reply text ("" on timeout)
    bool ok = false;         ///< the reply was "ok" (any case, surrounding blanks ignored)
    bool timed_out = false;
  };

  explicit SdkLink(double gap_s = 0.1) : pacer_(seconds_to_ns(gap_s)) {}

  /// Queues a non-rc command; it goes out once no command is outstanding and the gap since
  /// the last non-rc command has passed. A queued command not yet sent is replaced.
  void request(std::string text, double reply_timeout_s);
  /// Sends the queued command if it may go now.
  void poll(TimeNs now_ns, std::vector<SdkCommand>& out);
  /// A reply: completes the outstanding command, or is stale (nothing outstanding) and
  /// dropped (counted).
  std::optional<Completion> on_reply(const SdkReply& reply);
  /// The outstanding command, if its reply is overdue.
  std::optional<Completion> check_timeout(TimeNs now_ns);

  bool outstanding() const { return pacer_.outstanding() != nullptr; }
  bool idle() const { return !outstanding() && !queued_; }
  int stale_replies() const { return stale_replies_; }

 private:
  struct Queued {
    std::string text;
    TimeNs timeout_ns = 0;
  };
  CommandPacer<std::string> pacer_;  ///< the outstanding command's text
  std::optional<Queued> queued_;
  int stale_replies_ = 0;
};

}  // namespace shelfcross::flight_sw
