#pragma once
// The Tello SDK's rules for commands other than rc, written once (docs/tello_sdk.md, Session
// rules): replies carry no tag, so at most one such command is outstanding at a time; at
// least a gap passes between two of them (a re-send included); each waits for its reply no
// longer than its own timeout. rc gets no reply and is none of this pacer's business.
//
// The pacer holds the outstanding command (Command: whatever its user sends, with its own
// bookkeeping) and the times the rules need. It reads no clock: every time is the caller's
// "now". Queues, retries and what a reply means are the users' own: the flight software's
// MissionCommands (mission/commands.hpp: one command waiting, replaced by a newer one; the
// mission's retries and re-asks) and the Tello driver (a queue, retries, refusals, urgent
// commands).

#include <optional>
#include <string>
#include <utility>

#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

template <class Command>
class CommandPacer {
 public:
  /// gap_ns: the least time from one send (first or re-send) to the next.
  explicit CommandPacer(TimeNs gap_ns) : gap_ns_(gap_ns) {}

  /// True when a command may go out at now_ns: none is outstanding and the gap since the
  /// last send has passed.
  bool may_send(TimeNs now_ns) const {
    if (outstanding_) return false;
    return !sent_any_ || now_ns - last_sent_ns_ >= gap_ns_;
  }

  /// Records `command` as sent at now_ns and outstanding, its reply due within timeout_ns;
  /// returns it. Requires may_send(now_ns) (a command already outstanding is replaced).
  Command& send(TimeNs now_ns, Command command, TimeNs timeout_ns) {
    outstanding_ = Slot{std::move(command), now_ns, timeout_ns};
    sent_any_ = true;
    last_sent_ns_ = now_ns;
    return outstanding_->command;
  }

  /// The outstanding command went out again at now_ns: its timeout and the gap start anew.
  /// Requires an outstanding command.
  void resent(TimeNs now_ns) {
    outstanding_->sent_ns = now_ns;
    last_sent_ns_ = now_ns;
  }

  /// True when a command is outstanding and its reply timeout has run out at now_ns.
  bool overdue(TimeNs now_ns) const {
    return outstanding_ && now_ns - outstanding_->sent_ns >= outstanding_->timeout_ns;
  }

  /// The outstanding command, or null.
  Command* outstanding() { return outstanding_ ? &outstanding_->command : nullptr; }
  const Command* outstanding() const { return outstanding_ ? &outstanding_->command : nullptr; }

  /// Ends the outstanding command (replied, timed out or given up) and returns it; nothing
  /// when none is outstanding. The gap still runs from its last send.
  std::optional<Command> complete() {
    if (!outstanding_) return std::nullopt;
    std::optional<Command> done(std::move(outstanding_->command));
    outstanding_.reset();
    return done;
  }

 private:
  struct Slot {
    Command command;
    TimeNs sent_ns = 0;
    TimeNs timeout_ns = 0;
  };
  TimeNs gap_ns_;
  std::optional<Slot> outstanding_;
  // A flag and a time rather than std::optional<TimeNs>: GCC 12 at -O1 takes the optional's
  // value, read only when engaged, for maybe uninitialised (-Wmaybe-uninitialized).
  bool sent_any_ = false;    ///< a command has gone out
  TimeNs last_sent_ns_ = 0;  ///< the last send (first or re-send), when sent_any_
};

/// "ok" in any case, blanks around it ignored: the reply that accepts a command.
bool is_ok_reply(const std::string& text);

}  // namespace shelfcross::flight_sw
