#pragma once
// What the Tello driver's parts share (sdk_driver.hpp): the driver's configuration, a
// command's options, the events and counters it reports and the recorder of both, and the
// text of a datagram from the drone.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "flight_sw/tello/clock.hpp"
#include "sdk/command.hpp"
#include "sdk/state_record.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::tello {

struct DriverConfig {
  std::string drone_ip = "192.168.10.1";
  std::uint16_t drone_command_port = 8889;
  std::string local_ip = "0.0.0.0";
  std::uint16_t local_command_port = 0;  ///< 0: ephemeral (the drone replies to the sender)
  std::uint16_t local_state_port = 8890;
  std::uint16_t state_source_port = 0;   ///< 0: any port of drone_ip (undocumented on a Tello)
  sdk::ReplyTimeouts timeouts;
  int retries = 3;                       ///< re-sends after the first attempt
  TimeNs command_gap_ns = 100 * kMs;
  TimeNs stale_guard_ns = 300 * kMs;
  TimeNs refusal_retry_ns = 500 * kMs;   ///< re-send delay after a refusal (retry_unless_ok)
  TimeNs rc_period_ns = 100 * kMs;
  TimeNs rc_min_gap_ns = 20 * kMs;
  TimeNs rc_hold_ns = 1500 * kMs;
  TimeNs keepalive_ns = 5 * kNsPerSecond;  ///< 0 disables
  int stop_rc_repeats = 2;  ///< "rc 0 0 0 0" sent before a manoeuvre that follows deflected sticks
  /// New sticks go out this many times, rc_min_gap_ns apart, before the steady repeat: with
  /// datagram loss p, a change reaches the drone late (by rc_period_ns, 100 ms, instead of at
  /// most rc_min_gap_ns) with probability p^rc_new_copies instead of p. The calibration
  /// manoeuvre sends 3: its identification needs each step's edge where the log says it was.
  int rc_new_copies = 1;
  bool dry_run = false;
};

/// Per-command overrides of the driver's defaults.
struct CommandOptions {
  std::optional<TimeNs> timeout_ns;
  std::optional<int> retries;
  int tag = 0;          ///< the submitter's mark, echoed in the command's events
  bool urgent = false;  ///< abandon the outstanding and queued commands, clear rc, go next
  bool retry_unless_ok = false;  ///< a reply other than "ok" is a failed attempt (sdk_driver.hpp)
};

struct DriverEvent {
  enum class Kind {
    Sent,        ///< a non-rc command went out (attempt 1..)
    RcSent,      ///< an rc went out (setpoint, repeat, hover fallback)
    KeepAlive,   ///< the keep-alive rc went out
    Reply,       ///< the outstanding command's reply (text in `reply`)
    Refused,     ///< retry_unless_ok: refused (text in `reply`), re-sent after refusal_retry_ns
    Retry,       ///< no reply within the timeout, or not acted on (resend_unheard): re-sent
                 ///< (attempt = the new attempt)
    Failed,      ///< no reply after the last attempt
    Abandoned,   ///< an urgent command displaced this one
    StaleReply,  ///< a reply with nothing outstanding: dropped
    Foreign,     ///< a datagram from another address: dropped (`reply` = "from ip:port")
    BadReply,    ///< a reply with non-printable bytes or too long: dropped
    State,       ///< a parsed state record (`state`, raw text in `reply`)
    BadState,    ///< a state datagram that is no state record: dropped (raw text in `reply`)
    Filtered,    ///< dry run: a motion command that was not sent
    Rejected,    ///< an invalid command refused locally (`reply` = why)
  };
  TimeNs t_ns = 0;
  Kind kind = Kind::Sent;
  std::string command;
  std::string reply;
  int attempt = 0;
  int tag = 0;
  bool synthetic = false;  ///< a dry-run reply made up by the driver
  std::optional<StateRecord> state;
};
/// The kind's name for logs ("sent", "stale_reply", ...); "?" for a value that is no Kind.
const char* event_kind_name(DriverEvent::Kind kind);

struct DriverCounters {
  std::int64_t commands_sent = 0;   ///< non-rc datagrams, retries included
  std::int64_t retries = 0;
  std::int64_t failed = 0;
  std::int64_t replies = 0;
  std::int64_t refusals = 0;        ///< non-ok replies of retry_unless_ok commands, retried
  std::int64_t stale_replies = 0;
  std::int64_t bad_replies = 0;
  std::int64_t abandoned = 0;
  std::int64_t rc_sent = 0;
  std::int64_t keepalives = 0;
  std::int64_t filtered = 0;
  std::int64_t rejected = 0;
  std::int64_t send_errors = 0;
  std::int64_t foreign_command_datagrams = 0;
  std::int64_t foreign_state_datagrams = 0;
  std::int64_t states = 0;
  std::int64_t bad_states = 0;       ///< malformed state datagrams (stray "ok" included)
  std::int64_t stray_ok_states = 0;  ///< of which a stray "ok" (flight_sw::is_ok_reply: any case)
  std::string text() const;          ///< "name=value ..." on one line
};

/// The driver's events since they were last taken, and its counters. Each event is stamped
/// with the clock's time when it is recorded.
class DriverRecorder {
 public:
  /// Keeps a reference to `clock`: it must outlive the recorder.
  explicit DriverRecorder(const Clock& clock) : clock_(clock) {}
  /// The driver's parts keep references to it: it stays where it is.
  DriverRecorder(const DriverRecorder&) = delete;
  DriverRecorder& operator=(const DriverRecorder&) = delete;
  /// Records an event stamped with the clock's now; returns it for the fields set only by
  /// some events (the reference holds until the next add or take).
  DriverEvent& add(DriverEvent::Kind kind, const std::string& command, const std::string& reply = "",
                   int attempt = 0, int tag = 0);
  /// Events since the last call, in the order they happened.
  std::vector<DriverEvent> take();
  DriverCounters& counters() { return counters_; }
  const DriverCounters& counters() const { return counters_; }

 private:
  const Clock& clock_;
  std::vector<DriverEvent> events_;
  DriverCounters counters_;
};

/// A datagram's text without the blanks, "\r\n" and NULs real drones put around it.
std::string trim_reply(const std::string& raw);
/// True when every byte is printable ASCII (0x20..0x7e).
bool printable(const std::string& s);

}  // namespace shelfcross::tello
