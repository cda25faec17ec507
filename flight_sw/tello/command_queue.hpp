#pragma once
// The driver's commands other than rc (sdk_driver.hpp): a queue (urgent commands at its
// front), the SDK's rules kept by flight_sw::CommandPacer (one outstanding, the gap, the reply
// timeout), and what is the driver's own: re-sends when no reply comes, refusals re-sent
// (retry_unless_ok), stale replies dropped, and the stale guard after a command failed.

#include <deque>
#include <optional>
#include <string>

#include "flight_sw/mission/command_pacer.hpp"
#include "flight_sw/tello/command_wire.hpp"
#include "flight_sw/tello/sdk_driver_types.hpp"

namespace shelfcross::tello {

class CommandQueue {
 public:
  /// Keeps references to all three: they must outlive the queue.
  CommandQueue(const DriverConfig& config, CommandWire& wire, DriverRecorder& recorder);

  /// Queues a valid non-rc command (urgent: at the front). False when the queue is full
  /// (Rejected event).
  bool submit(const std::string& text, const CommandOptions& options);
  /// Abandons the outstanding command and every queued one (Abandoned events); the next
  /// command need not wait for the stale guard.
  void abandon_all();
  /// Reads the drone's replies: each completes the outstanding command (Reply), is a refusal
  /// to re-send (Refused), or is stale (nothing waits for a reply) or bad, and dropped.
  void read_replies(TimeNs now);
  /// Re-sends a refused command when due; a command without reply within its timeout is
  /// re-sent (Retry) while retries remain, else it fails (Failed) and the stale guard starts.
  void check_timeout(TimeNs now);
  /// Re-sends the outstanding command at now, before its timeout, when it is `text`, retries
  /// remain and it is not waiting out a refusal (Retry): its caller saw that the drone did
  /// not act on it. True when re-sent.
  bool resend_unheard(TimeNs now, const std::string& text);
  /// The text of the next queued command when it may go at now, else null.
  const std::string* next_due(TimeNs now) const;
  /// Drains the replies waiting (stale by now) and sends the next queued command; it is
  /// outstanding even when the OS refused the send. Requires next_due(now).
  void send_next(TimeNs now);

  bool outstanding() const { return pacer_.outstanding() != nullptr; }
  bool idle() const { return !outstanding() && queue_.empty(); }

 private:
  struct Pending {
    std::string text;
    CommandOptions options;
    TimeNs timeout_ns = 0;  ///< the reply timeout it is sent with
    int retries = 0;
    int attempt = 0;
    std::optional<TimeNs> resend_ns;  ///< refused: re-send at this time
  };
  void resend(TimeNs now);
  /// Records a send of the outstanding command (Sent), if the wire took it.
  void transmit(TimeNs now, const Pending& p);

  const DriverConfig& config_;
  CommandWire& wire_;
  DriverRecorder& recorder_;
  flight_sw::CommandPacer<Pending> pacer_;  ///< the outstanding command; the gap, the timeout
  std::deque<Pending> queue_;
  TimeNs guard_until_ns_ = 0;  ///< after a failure: the next command waits for its late reply
};

}  // namespace shelfcross::tello
