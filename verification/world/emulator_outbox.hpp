#pragma once
// The Tello emulator's datagram channels and what goes out on them: the command socket
// (commands in, replies out), the state and video sockets (out), every fault draw
// (DatagramFaults: loss, duplication, late replies, each channel's delay), the datagrams held
// until they fall due, in due order (ties: in the order queued), and the counters. The
// emulator's main loop and its video worker share it under one mutex: every function named
// *_locked requires it held (lock()). Internal to the emulator (tello_emulator.cpp and its
// parts).

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <queue>
#include <string>
#include <vector>

#include "shelfcross/time.hpp"
#include "verification/world/datagram_faults.hpp"
#include "verification/world/tello_emulator_settings.hpp"

namespace shelfcross::verification {

class EmulatorOutbox {
 public:
  /// Binds a UDP socket for each channel the caller does not give (config's bind_ip and
  /// ports); the fault streams from config.seed. Throws std::invalid_argument (bad address),
  /// std::runtime_error (port busy).
  EmulatorOutbox(EmulatorChannels channels, const EmulatorConfig& config);

  std::unique_lock<std::mutex> lock() const { return std::unique_lock(mutex_); }
  /// Where commands are read from (the main loop alone reads it).
  tello::DatagramChannel& command_socket() { return *command_socket_; }
  EmulatorPorts ports() const;
  DatagramFaults& faults_locked() { return faults_; }
  EmulatorCounters& counters_locked() { return counters_; }
  const EmulatorCounters& counters_locked() const { return counters_; }

  /// A reply sent at t to `to`: lost, late (held back late_reply_ms more) or duplicated as
  /// drawn (three draws, always), queued for its channel's delivery time.
  void send_reply_locked(TimeNs t, const std::string& text, const tello::Endpoint& to);
  /// A state record sent at t to `to`: lost or duplicated as drawn (two draws, always).
  void send_state_locked(TimeNs t, const std::string& text, const tello::Endpoint& to);
  /// An encoded frame captured at t_capture (key: it holds an IDR picture): one delay for the
  /// whole frame (its datagrams leave back to back), a loss draw per datagram; then sends
  /// everything due by t_send.
  void send_frame_locked(TimeNs t_capture, std::vector<std::string> datagrams, bool key, const tello::Endpoint& to,
                         TimeNs t_send);
  /// Sends every queued datagram due by now_ns, in due order.
  void flush_locked(TimeNs now_ns);
  /// The earlier of t and the first queued datagram's due time.
  TimeNs next_due_locked(TimeNs t) const;

 private:
  enum class Channel { reply, state, video };
  struct Outgoing {
    TimeNs due_ns;
    std::uint64_t seq;
    Channel channel;
    tello::Endpoint to;
    std::string bytes;
    bool operator>(const Outgoing& o) const { return due_ns != o.due_ns ? due_ns > o.due_ns : seq > o.seq; }
  };
  void queue_locked(TimeNs due_ns, Channel channel, const tello::Endpoint& to, std::string bytes);

  std::unique_ptr<tello::DatagramChannel> command_socket_, state_socket_, video_socket_;
  DatagramFaults faults_;
  mutable std::mutex mutex_;
  std::priority_queue<Outgoing, std::vector<Outgoing>, std::greater<>> outgoing_;
  std::uint64_t seq_ = 0;
  EmulatorCounters counters_;
};

}  // namespace shelfcross::verification
