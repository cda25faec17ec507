#pragma once
// A non-blocking IPv4 UDP socket (POSIX), the one networking primitive of the Tello driver.
// Every receive reports the sender, so callers can drop datagrams that do not come from the
// drone (docs/tello_sdk.md: replies come from drone_ip:8889; state and video from drone_ip).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <netinet/in.h>

namespace shelfcross::tello {

/// An IPv4 address and port. `ip` is dotted-quad text ("192.168.10.1").
struct Endpoint {
  std::string ip;
  std::uint16_t port = 0;
  bool operator==(const Endpoint&) const = default;
  std::string text() const { return ip + ":" + std::to_string(port); }
};

/// Parses dotted-quad IPv4 text; throws std::invalid_argument naming the text otherwise.
in_addr parse_ipv4(const std::string& ip);

struct Datagram {
  std::string bytes;
  Endpoint from;
};

/// One local datagram endpoint: what the driver and the video receiver read and write. A
/// UdpSocket in tello_pilot and the emulator; a MemoryChannel (datagram_channel.hpp) when the
/// co-simulation carries the datagrams itself, in simulated time.
class DatagramChannel {
 public:
  virtual ~DatagramChannel() = default;
  /// Sends one datagram; false when it cannot go out (the OS refused it).
  virtual bool send_to(const Endpoint& to, std::string_view bytes) = 0;
  /// The next datagram that has arrived, or nothing (never blocks).
  virtual std::optional<Datagram> receive() = 0;
  /// A file descriptor that polls readable when a datagram waits; -1 when there is none
  /// (in-memory channels: their owner knows when it delivered something).
  virtual int fd() const { return -1; }
  virtual std::uint16_t local_port() const = 0;
};

class UdpSocket final : public DatagramChannel {
 public:
  /// Binds to local_ip:local_port (port 0: an ephemeral port, see local_port()).
  /// `receive_buffer_bytes` > 0 asks the kernel for that receive buffer (video needs room
  /// for bursts of key frames). Throws std::runtime_error with the OS's reason on failure
  /// ("address already in use" when another program holds the Tello's ports).
  UdpSocket(const std::string& local_ip, std::uint16_t local_port, int receive_buffer_bytes = 0);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;

  int fd() const override { return fd_; }
  std::uint16_t local_port() const override { return local_port_; }

  /// Sends one datagram; returns false (errno kept) when the OS refuses it.
  bool send_to(const Endpoint& to, std::string_view bytes) override;
  /// The next pending datagram, or nothing when none waits (never blocks).
  std::optional<Datagram> receive() override;
  /// Waits up to timeout_ms for a datagram to be readable (poll); true when one is.
  bool wait_readable(int timeout_ms) const;

 private:
  void close_fd();
  int fd_ = -1;
  std::uint16_t local_port_ = 0;
  std::string buffer_;
};

}  // namespace shelfcross::tello
