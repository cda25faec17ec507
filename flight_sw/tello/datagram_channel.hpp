#pragma once
// An in-memory datagram endpoint: the co-simulation's stand-in for a UDP socket, so that the
// driver, the video receiver and the pilot loop that fly a real Tello run unchanged in
// simulated time. Whoever carries the datagrams (verification's datagram link) takes what
// the owner sent with take_sent() and hands arriving datagrams in with deliver(); nothing
// here reads a clock or blocks. Single-threaded: the co-simulation runs the video receiver
// inline (VideoReceiverConfig::threaded = false).

#include <deque>
#include <string>
#include <vector>

#include "flight_sw/tello/udp_socket.hpp"

namespace shelfcross::tello {

/// A datagram on its way out: its destination and bytes.
struct OutgoingDatagram {
  Endpoint to;
  std::string bytes;
};

class MemoryChannel final : public DatagramChannel {
 public:
  explicit MemoryChannel(Endpoint local) : local_(std::move(local)) {}

  bool send_to(const Endpoint& to, std::string_view bytes) override {
    sent_.push_back({to, std::string(bytes)});
    return true;
  }
  std::optional<Datagram> receive() override {
    if (inbox_.empty()) return std::nullopt;
    Datagram d = std::move(inbox_.front());
    inbox_.pop_front();
    return d;
  }
  std::uint16_t local_port() const override { return local_.port; }
  const Endpoint& local() const { return local_; }

  /// A datagram has arrived (it is read by the next receive()).
  void deliver(Datagram d) { inbox_.push_back(std::move(d)); }
  /// What was sent since the last call, oldest first.
  std::vector<OutgoingDatagram> take_sent() {
    std::vector<OutgoingDatagram> out;
    out.swap(sent_);
    return out;
  }
  bool has_sent() const { return !sent_.empty(); }
  bool has_inbox() const { return !inbox_.empty(); }

 private:
  Endpoint local_;
  std::deque<Datagram> inbox_;
  std::vector<OutgoingDatagram> sent_;
};

}  // namespace shelfcross::tello
