#include "flight_sw/tello/command_wire.hpp"

#include <arpa/inet.h>

namespace shelfcross::tello {

CommandWire::CommandWire(const std::string& drone_ip, std::uint16_t drone_port,
                         std::unique_ptr<DatagramChannel> channel, DriverRecorder& recorder)
    : drone_{drone_ip, drone_port}, channel_(std::move(channel)), recorder_(recorder) {
  // Refuse a bad address now, not at the first send; compare senders in canonical text form.
  char canonical[INET_ADDRSTRLEN] = {};
  const in_addr a = parse_ipv4(drone_ip);
  ::inet_ntop(AF_INET, &a, canonical, sizeof canonical);
  drone_.ip = canonical;
}

bool CommandWire::transmit(TimeNs now, const std::string& text) {
  // Every datagram passes the SDK's ranges once more, whatever path it took here.
  std::string why;
  if (!sdk::classify_command(text, &why)) {
    ++recorder_.counters().rejected;
    recorder_.add(DriverEvent::Kind::Rejected, text, why);
    return false;
  }
  last_sent_ns_ = now;
  if (!channel_->send_to(drone_, text)) {
    ++recorder_.counters().send_errors;
    return false;
  }
  return true;
}

std::optional<std::string> CommandWire::receive() {
  while (auto d = channel_->receive()) {
    if (d->from == drone_) return std::move(d->bytes);
    ++recorder_.counters().foreign_command_datagrams;
    recorder_.add(DriverEvent::Kind::Foreign, "", "command socket: from " + d->from.text());
  }
  return std::nullopt;
}

}  // namespace shelfcross::tello
