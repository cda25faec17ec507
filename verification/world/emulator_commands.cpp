#include "verification/world/emulator_commands.hpp"

#include <algorithm>
#include <exception>
#include <variant>

#include "sdk/command.hpp"

namespace shelfcross::verification {
namespace {

/// A command datagram the firmware may see: 1..max bytes of printable ASCII, optionally
/// ended by "\r\n" or "\n" (the firmware trims whitespace).
bool well_formed(const std::string& bytes, std::size_t max_bytes) {
  if (bytes.empty() || bytes.size() > max_bytes) return false;
  return std::all_of(bytes.begin(), bytes.end(), [](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return (c >= 0x20 && c < 0x7f) || c == '\r' || c == '\n';
  });
}

/// Manoeuvres a real Tello refuses with "error Not joystick" / "error No valid imu". Land and
/// emergency are never refused here, so a client can always end a flight.
bool refusable(const std::string& text) {
  const auto parsed = sdk::parse(text);
  const auto* c = std::get_if<sdk::Command>(&parsed);
  return c && sdk::is_manoeuvre(c->verb) && c->verb != sdk::Verb::land;
}

bool is_manoeuvre_text(const std::string& text) {
  const auto parsed = sdk::parse(text);
  const auto* c = std::get_if<sdk::Command>(&parsed);
  return c && sdk::is_manoeuvre(c->verb);
}

}  // namespace

SdkCommandInterpreter::SdkCommandInterpreter(std::size_t max_datagram_bytes) : max_datagram_bytes_(max_datagram_bytes) {}

void SdkCommandInterpreter::receive(TimeNs now_ns, EmulatorOutbox& outbox) {
  while (auto d = outbox.command_socket().receive()) {
    last_datagram_ns_ = now_ns;
    const auto lock = outbox.lock();
    EmulatorCounters& counters = outbox.counters_locked();
    ++counters.commands_received;
    if (!well_formed(d->bytes, max_datagram_bytes_)) {
      ++counters.commands_malformed;
      continue;
    }
    DatagramFaults& faults = outbox.faults_locked();
    const DatagramFaults::Fate fate = faults.command(d->bytes, now_ns);
    if (fate.lost) {
      ++counters.commands_dropped;
      continue;
    }
    const TimeNs due = faults.due(DatagramFaults::Channel::command, now_ns);
    incoming_.push({due, seq_++, d->bytes, d->from});
    if (fate.twice) {
      ++counters.commands_duplicated;
      incoming_.push({due, seq_++, d->bytes, d->from});
    }
  }
}

std::optional<std::string> SdkCommandInterpreter::deliver_due(TimeNs t, plant::SimulatedTello& tello,
                                                              EmulatorOutbox& outbox) {
  std::optional<std::string> failure;
  while (!incoming_.empty() && incoming_.top().due_ns <= t && !failure) {
    const IncomingCommand c = incoming_.top();
    incoming_.pop();
    failure = deliver(t, c, tello, outbox);
  }
  for (const SdkReply& reply : tello.take_replies()) {
    const auto lock = outbox.lock();
    outbox.send_reply_locked(reply.t_ns, reply.text, manoeuvre_reply_to_);
  }
  return failure;
}

std::optional<std::string> SdkCommandInterpreter::deliver(TimeNs t, const IncomingCommand& c,
                                                          plant::SimulatedTello& tello, EmulatorOutbox& outbox) {
  std::string text = c.text;
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  {
    const auto lock = outbox.lock();
    ++outbox.counters_locked().commands_delivered;
  }
  if (tello.autopilot().sdk_mode() && refusable(text)) {
    std::unique_lock lock = outbox.lock();
    const DatagramFaults::Refusal refusal = outbox.faults_locked().refusal();
    const bool joystick = refusal.not_joystick, imu = refusal.no_valid_imu;
    if (joystick || imu) {
      ++outbox.counters_locked().injected_errors;
      lock.unlock();
      // The drone received a command and answered it: that counts for its 15 s no-command
      // watchdog like any other ("any command counts", docs/tello_sdk.md). The simulated firmware
      // only learns of a datagram through a command, so it is handed the one command with no
      // effect but an immediate answer, a read, whose answer is dropped.
      try {
        (void)tello.submit(t, "sdk?");
      } catch (const std::exception& e) {
        return e.what();
      }
      lock.lock();
      outbox.send_reply_locked(t, joystick ? "error Not joystick" : "error No valid imu", c.from);
      return std::nullopt;
    }
  }
  if (is_manoeuvre_text(text)) manoeuvre_reply_to_ = c.from;
  std::optional<std::string> reply;
  try {
    reply = tello.submit(t, text);
  } catch (const std::exception& e) {
    return e.what();
  }
  if (text == "command" && reply == "ok") client_ = c.from;
  if (reply) {
    const auto lock = outbox.lock();
    outbox.send_reply_locked(t, *reply, c.from);
  }
  return std::nullopt;
}

}  // namespace shelfcross::verification
