#pragma once
// The command side of the Tello SDK as docs/tello_sdk.md describes it: one non-rc command
// outstanding at a time (replies carry no tag), a gap between non-rc commands, a reply
// timeout per command; rc commands need no reply and go out at once. Time is the stamp of
// the input being handled; nothing here reads a clock.

#include <optional>
#include <string>
#include <vector>

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

  explicit SdkLink(double gap_s = 0.1) : gap_ns_(seconds_to_ns(gap_s)) {}

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

  bool outstanding() const { return outstanding_.has_value(); }
  bool idle() const { return !outstanding_ && !queued_; }
  int stale_replies() const { return stale_replies_; }

 private:
  struct Pending {
    std::string text;
    TimeNs timeout_ns = 0;
    TimeNs sent_ns = 0;
  };
  TimeNs gap_ns_;
  std::optional<Pending> queued_;
  std::optional<Pending> outstanding_;
  std::optional<TimeNs> last_sent_ns_;
  int stale_replies_ = 0;
};

/// "ok" in any case, blanks around it ignored.
bool is_ok_reply(const std::string& text);

}  // namespace shelfcross::flight_sw
