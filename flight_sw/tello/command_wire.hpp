#pragma once
// The driver's command socket (sdk_driver.hpp): every text it sends passes the SDK's grammar
// and ranges once more (sdk::classify_command) on its way out; what it reads is only the
// drone's (datagrams from any other address are dropped and counted).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "flight_sw/tello/sdk_driver_types.hpp"
#include "flight_sw/tello/udp_socket.hpp"

namespace shelfcross::tello {

class CommandWire {
 public:
  /// Sends to and reads from drone_ip:drone_port over `channel`; records into `recorder`,
  /// which must outlive the wire. Throws std::invalid_argument when drone_ip is no IPv4
  /// address.
  CommandWire(const std::string& drone_ip, std::uint16_t drone_port, std::unique_ptr<DatagramChannel> channel,
              DriverRecorder& recorder);

  /// Sends `text` to the drone at now. False when it is no valid SDK command (Rejected event,
  /// not sent) or the OS refused the send (counted).
  bool transmit(TimeNs now, const std::string& text);
  /// The next datagram from the drone's command port, or nothing when none waits.
  std::optional<std::string> receive();

  /// The drone's address in canonical dotted-quad text (senders are compared in this form).
  const std::string& drone_ip() const { return drone_.ip; }
  /// When the last datagram of any kind was handed to the socket; nothing before the first.
  std::optional<TimeNs> last_sent_ns() const { return last_sent_ns_; }
  std::uint16_t local_port() const { return channel_->local_port(); }
  int fd() const { return channel_->fd(); }

 private:
  Endpoint drone_;
  std::unique_ptr<DatagramChannel> channel_;
  DriverRecorder& recorder_;
  std::optional<TimeNs> last_sent_ns_;
};

}  // namespace shelfcross::tello
