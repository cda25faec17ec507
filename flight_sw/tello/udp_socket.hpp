#pragma once
// A non-blocking IPv4 UDP socket (POSIX), the one networking primitive of the Tello driver.
// Every receive reports the sender, so callers can drop datagrams that do not come from the
// drone (PROTOCOL.md: replies come from drone_ip:8889; state and video from drone_ip).

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

class UdpSocket {
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

  int fd() const { return fd_; }
  std::uint16_t local_port() const { return local_port_; }

  /// Sends one datagram; returns false (errno kept) when the OS refuses it.
  bool send_to(const Endpoint& to, std::string_view bytes);
  /// The next pending datagram, or nothing when none waits (never blocks).
  std::optional<Datagram> receive();
  /// Waits up to timeout_ms for a datagram to be readable (poll); true when one is.
  bool wait_readable(int timeout_ms) const;

 private:
  void close_fd();
  int fd_ = -1;
  std::uint16_t local_port_ = 0;
  std::string buffer_;
};

}  // namespace shelfcross::tello
