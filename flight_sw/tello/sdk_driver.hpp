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
//    software's MissionCommands keeps them with the same pacer): one outstanding at a time,
//    queued commands wait for its reply or timeout; at least command_gap_ns between two
//    sends; each waits for its reply (sdk::ReplyTimeouts: 7 s, 20 s for takeoff, 10 s for land);
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
//
// Its parts: command_queue.hpp (the non-rc commands: queue, pacer, retries, refusals,
// replies), rc_repeater.hpp (the stick input), command_wire.hpp (the command socket),
// state_listener.hpp (the state socket), sdk_driver_types.hpp (configuration, events,
// counters).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/command_queue.hpp"
#include "flight_sw/tello/command_wire.hpp"
#include "flight_sw/tello/rc_repeater.hpp"
#include "flight_sw/tello/sdk_driver_types.hpp"
#include "flight_sw/tello/state_listener.hpp"
#include "flight_sw/tello/udp_socket.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::tello {

/// Neither copied nor moved (its parts refer to one another).
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

  /// Re-sends the outstanding command now if it is `text` and retries remain (the caller
  /// saw the drone not act on it); true when sent. CommandQueue::resend_unheard.
  bool resend_unheard(const std::string& text) { return commands_.resend_unheard(clock_.now_ns(), text); }

  /// Events since the last call, in the order they happened.
  std::vector<DriverEvent> take_events() { return recorder_.take(); }

  bool outstanding() const { return commands_.outstanding(); }
  bool idle() const { return commands_.idle(); }
  std::optional<TimeNs> last_state_ns() const { return state_.last_state_ns(); }
  const DriverCounters& counters() const { return recorder_.counters(); }
  const DriverConfig& config() const { return config_; }
  std::uint16_t local_command_port() const { return wire_.local_port(); }
  std::uint16_t local_state_port() const { return state_.local_port(); }
  int command_fd() const { return wire_.fd(); }
  int state_fd() const { return state_.fd(); }

 private:
  /// The next queued command, if it may go; a manoeuvre after deflected sticks first waits
  /// for centred ones.
  void send_next(TimeNs now);
  /// The rc setpoint when due (never while a command waits for its reply), else the
  /// keep-alive when due.
  void send_rc(TimeNs now);
  void transmit_rc(TimeNs now, const std::string& text, DriverEvent::Kind kind);

  DriverConfig config_;
  const Clock& clock_;
  DriverRecorder recorder_;
  CommandWire wire_;
  StateListener state_;
  CommandQueue commands_;
  RcRepeater rc_;
};

}  // namespace shelfcross::tello
