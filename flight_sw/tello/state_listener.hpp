#pragma once
// The driver's state socket (sdk_driver.hpp): the drone's 10 Hz state records, parsed
// (sdk::parse_state_record) into State events; datagrams from anyone but the drone and
// datagrams that are no state record are dropped and counted.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "flight_sw/tello/sdk_driver_types.hpp"
#include "flight_sw/tello/udp_socket.hpp"

namespace shelfcross::tello {

class StateListener {
 public:
  /// Takes state records from drone_ip (canonical dotted-quad text) and, when source_port is
  /// not 0, from that port only; records into `recorder`, which must outlive the listener.
  StateListener(std::string drone_ip, std::uint16_t source_port, std::unique_ptr<DatagramChannel> channel,
                DriverRecorder& recorder);

  /// Reads every waiting datagram; `now` stamps the records.
  void read(TimeNs now);
  /// When the newest state record arrived; nothing before the first.
  std::optional<TimeNs> last_state_ns() const { return last_state_ns_; }
  std::uint16_t local_port() const { return channel_->local_port(); }
  int fd() const { return channel_->fd(); }

 private:
  std::string drone_ip_;
  std::uint16_t source_port_;
  std::unique_ptr<DatagramChannel> channel_;
  DriverRecorder& recorder_;
  std::optional<TimeNs> last_state_ns_;
};

}  // namespace shelfcross::tello
