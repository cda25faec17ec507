#include "flight_sw/tello/state_listener.hpp"

#include "flight_sw/mission/command_pacer.hpp"

namespace shelfcross::tello {

StateListener::StateListener(std::string drone_ip, std::uint16_t source_port,
                             std::unique_ptr<DatagramChannel> channel, DriverRecorder& recorder)
    : drone_ip_(std::move(drone_ip)), source_port_(source_port), channel_(std::move(channel)), recorder_(recorder) {}

void StateListener::read(TimeNs now) {
  DriverCounters& counters = recorder_.counters();
  while (auto d = channel_->receive()) {
    const bool from_drone = d->from.ip == drone_ip_ && (source_port_ == 0 || d->from.port == source_port_);
    if (!from_drone) {
      ++counters.foreign_state_datagrams;
      recorder_.add(DriverEvent::Kind::Foreign, "", "state socket: from " + d->from.text());
      continue;
    }
    sdk::StateParseReport report;
    auto record = sdk::parse_state_record(d->bytes, now, &report);
    const std::string raw = trim_reply(d->bytes);
    if (!record) {
      ++counters.bad_states;
      if (flight_sw::is_ok_reply(raw)) ++counters.stray_ok_states;
      std::string shown = raw;
      if (!printable(raw)) shown = std::to_string(d->bytes.size()).append(" bytes, not text");
      recorder_.add(DriverEvent::Kind::BadState, "", shown);
      continue;
    }
    ++counters.states;
    last_state_ns_ = now;
    recorder_.add(DriverEvent::Kind::State, "", raw).state = std::move(record);
  }
}

}  // namespace shelfcross::tello
