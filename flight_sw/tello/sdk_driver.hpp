#pragma once
// The Tello text-SDK driver over UDP (docs/tello_sdk.md): the command socket (commands
// out, replies in, from one local port) and the state socket (the 10 Hz state records).
// Single-threaded: the owner calls service() whenever one of fds() is readable or a short
// poll timeout passes; service() reads every pending datagram, fires timers and sends what is
// due. All times come from the Clock it is given (tests step a ManualClock).
//
// Command rules it enforces:
//  - every outgoing text is validated (sdk::classify_command): an unknown command or an argument
//    out of the SDK's range is refused locally and never sent;
//  - the SDK's rules for non-rc commands, kept by flight_sw::CommandPacer (the flight
//    software's SdkLink keeps them with the same pacer): one outstanding at a time, queued
//    commands wait for its reply or timeout; at least command_gap_ns between two sends;
//    each waits for its reply (ReplyTimeouts: 7 s, 20 s for takeoff);
//  - the driver's own: a command is re-sent up to `retries` times when no reply comes; then
//    it fails;
//  - a refusal ("error", "error Not joystick", "error No valid imu", ...: any reply but "ok")
//    completes the command (Reply event) unless CommandOptions::retry_unless_ok: then it is a
//    failed attempt (Refused event) and the command is re-sent refusal_retry_ns later while
//    retries remain (the last refusal is the Reply). The program's own `land` uses this: a
//    real Tello refuses manoeuvres with these errors, and a land must not be given up on at
//    the first refusal. Every refusal is a command the drone received: it counts for its 15 s
//    watchdog like any other (the emulator does the same);
//  - replies carry no tag, so a reply that arrives when nothing is outstanding is stale and
//    dropped; pending replies are drained (dropped as stale) right before each non-rc send,
//    and after a command timed out the next one waits stale_guard_ns more for its late reply;
//  - rc gets no reply and is never waited for: the latest rc setpoint is sent at once (and
//    again rc_new_copies - 1 times, rc_min_gap_ns apart) and repeated every rc_period_ns while
//    it is fresh (set within rc_hold_ns); an rc not renewed for rc_hold_ns falls back to
//    "rc 0 0 0 0" (hover);
//  - a manoeuvre (takeoff, land, moves, ...; not emergency) that follows deflected sticks
//    waits until "rc 0 0 0 0" went out stop_rc_repeats times, rc_min_gap_ns apart: the drone
//    flies the last sticks it got, so a lost `land` must leave it hovering, not flying on;
//  - keep-alive: when nothing was sent for keepalive_ns, "rc 0 0 0 0" goes out, so the
//    drone's 15 s no-command watchdog never lands it by surprise (rc is the one command that
//    gets no reply, so it never disturbs the outstanding command);
//  - datagrams from anyone but the drone are dropped and counted: replies must come from
//    drone_ip:drone_command_port, state records from drone_ip (and state_source_port if set);
//  - dry run: motion commands (takeoff, land, moves, rc, ...) are never sent; they are
//    reported as Filtered and non-rc ones get a synthetic "ok" so the flight software runs on
//    (perception with the drone carried by hand).

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flight_sw/command_pacer.hpp"
#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/udp_socket.hpp"
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
  bool retry_unless_ok = false;  ///< a reply other than "ok" is a failed attempt (see above)
};

struct DriverEvent {
  enum class Kind {
    Sent,        ///< a non-rc command went out (attempt 1..)
    RcSent,      ///< an rc went out (setpoint, repeat, hover fallback)
    KeepAlive,   ///< the keep-alive rc went out
    Reply,       ///< the outstanding command's reply (text in `reply`)
    Refused,     ///< retry_unless_ok: refused (text in `reply`), re-sent after refusal_retry_ns
    Retry,       ///< no reply within the timeout: re-sent (attempt = the new attempt)
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
  std::int64_t stray_ok_states = 0;  ///< of which a stray "ok"
  std::string text() const;          ///< "name=value ..." on one line
};

class SdkDriver {
 public:
  /// Binds the command and state sockets; throws std::runtime_error (port busy) or
  /// std::invalid_argument (bad address).
  SdkDriver(DriverConfig config, const Clock& clock);
  /// The same driver on channels of the caller's (the co-simulation's in-memory ones);
  /// config's local ports and address are not used.
  SdkDriver(DriverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> command_channel,
            std::unique_ptr<DatagramChannel> state_channel);

  /// Hands a command over. rc: becomes the setpoint (sent by service()). Others: queued.
  /// Returns false when the text was refused (invalid: Rejected event) or filtered (dry run).
  bool submit(const std::string& text, const CommandOptions& options = {});

  /// Reads every pending datagram, fires timeouts and retries, sends what is due.
  void service();

  /// Events since the last call, in the order they happened.
  std::vector<DriverEvent> take_events();

  bool outstanding() const { return pacer_.outstanding() != nullptr; }
  bool idle() const { return !outstanding() && queue_.empty(); }
  std::optional<TimeNs> last_state_ns() const { return last_state_ns_; }
  const DriverCounters& counters() const { return counters_; }
  const DriverConfig& config() const { return config_; }
  std::uint16_t local_command_port() const { return command_channel_->local_port(); }
  std::uint16_t local_state_port() const { return state_channel_->local_port(); }
  int command_fd() const { return command_channel_->fd(); }
  int state_fd() const { return state_channel_->fd(); }

 private:
  struct Pending {
    std::string text;
    CommandOptions options;
    TimeNs timeout_ns = 0;  ///< the reply timeout it is sent with
    int retries = 0;
    int attempt = 0;
    std::optional<TimeNs> resend_ns;  ///< refused: re-send at this time
  };
  void event(DriverEvent::Kind kind, const std::string& command, const std::string& reply = "",
             int attempt = 0, int tag = 0);
  void read_replies(TimeNs now);
  void read_states(TimeNs now);
  void check_timeout(TimeNs now);
  void resend(TimeNs now);
  void send_next(TimeNs now);
  void send_rc(TimeNs now);
  void transmit_rc(TimeNs now, const std::string& text, DriverEvent::Kind kind);
  bool transmit(TimeNs now, const std::string& text);

  DriverConfig config_;
  flight_sw::CommandPacer<Pending> pacer_;  ///< the outstanding command; the gap, the timeout
  const Clock& clock_;
  Endpoint drone_command_;
  std::unique_ptr<DatagramChannel> command_channel_;
  std::unique_ptr<DatagramChannel> state_channel_;
  std::deque<Pending> queue_;
  std::optional<TimeNs> last_any_ns_;      ///< last datagram of any kind sent
  TimeNs guard_until_ns_ = 0;
  // rc setpoint
  std::optional<std::string> rc_setpoint_;
  TimeNs rc_set_ns_ = 0;
  int rc_new_owed_ = 0;  ///< copies of new sticks still to send (rc_new_copies)
  std::optional<TimeNs> last_rc_ns_;
  int stops_owed_ = 0;  ///< "rc 0 0 0 0" still to send before a manoeuvre (stop_rc_repeats after deflected sticks)
  std::optional<TimeNs> last_state_ns_;
  DriverCounters counters_;
  std::vector<DriverEvent> events_;
};

}  // namespace shelfcross::tello
