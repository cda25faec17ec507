#pragma once
// The Tello emulator's SDK command interpreter: command datagrams read and checked (well
// formed, the command channel's fault draws, the lost-prefix injection), held until their
// delivery time, handed to the firmware at the first tick after it; the injected refusals of
// manoeuvres ("error Not joystick", "error No valid imu"); every reply addressed (a command's
// to its sender, the firmware's deferred manoeuvre replies to the latest manoeuvre's sender);
// and the client, the sender of `command`, whom state and video go to. Main loop only.
// Internal to the emulator (tello_emulator.cpp).

#include <cstdint>
#include <functional>
#include <optional>
#include <queue>
#include <string>
#include <vector>

#include "flight_sw/tello/udp_socket.hpp"
#include "plant/simulated_tello.hpp"
#include "shelfcross/time.hpp"
#include "verification/world/emulator_outbox.hpp"

namespace shelfcross::verification {

class SdkCommandInterpreter {
 public:
  /// Longer command datagrams are malformed. Which datagrams are lost (drawn, or injected by
  /// EmulatorFaults::lost_command_prefix) the outbox's DatagramFaults says.
  explicit SdkCommandInterpreter(std::size_t max_datagram_bytes);

  /// Reads every pending command datagram (stamped now_ns) and queues the ones that arrive
  /// for their delivery time.
  void receive(TimeNs now_ns, EmulatorOutbox& outbox);
  /// Hands the commands due by t to the firmware (their replies queued), then queues the
  /// firmware's deferred replies. Stops handing commands at the first that the firmware
  /// throws on (a numerical failure of the plant) and returns its message; nullopt otherwise.
  std::optional<std::string> deliver_due(TimeNs t, plant::SimulatedTello& tello, EmulatorOutbox& outbox);

  /// The sender of `command` (answered ok), if one came.
  const std::optional<tello::Endpoint>& client() const { return client_; }
  /// When the last command datagram was read (0 before the first).
  TimeNs last_datagram_ns() const { return last_datagram_ns_; }

 private:
  struct IncomingCommand {
    TimeNs due_ns;
    std::uint64_t seq;
    std::string text;
    tello::Endpoint from;
    bool operator>(const IncomingCommand& o) const { return due_ns != o.due_ns ? due_ns > o.due_ns : seq > o.seq; }
  };
  /// One command to the firmware; the firmware's exception message if it threw.
  std::optional<std::string> deliver(TimeNs t, const IncomingCommand& command, plant::SimulatedTello& tello,
                                     EmulatorOutbox& outbox);

  std::size_t max_datagram_bytes_;
  std::priority_queue<IncomingCommand, std::vector<IncomingCommand>, std::greater<>> incoming_;
  std::uint64_t seq_ = 0;
  TimeNs last_datagram_ns_ = 0;
  std::optional<tello::Endpoint> client_;  ///< the sender of `command`
  tello::Endpoint manoeuvre_reply_to_;     ///< the sender of the latest non-rc command
};

}  // namespace shelfcross::verification
