#include "flight_sw/tello/udp_socket.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace shelfcross::tello {
namespace {

// The largest UDP payload over IPv4.
constexpr size_t kMaxDatagram = 65507;

sockaddr_in to_sockaddr(const Endpoint& e) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr = parse_ipv4(e.ip);
  a.sin_port = htons(e.port);
  return a;
}

}  // namespace

in_addr parse_ipv4(const std::string& ip) {
  in_addr a{};
  if (inet_pton(AF_INET, ip.c_str(), &a) != 1) {
    throw std::invalid_argument("'" + ip + "' is not an IPv4 address (dotted quad expected)");
  }
  return a;
}

UdpSocket::UdpSocket(const std::string& local_ip, std::uint16_t local_port,
                     int receive_buffer_bytes)
    : buffer_(kMaxDatagram, '\0') {
  const sockaddr_in local = to_sockaddr({local_ip, local_port});
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("UDP socket: ") + std::strerror(errno));
  if (receive_buffer_bytes > 0) {
    // SO_RCVBUFFORCE passes rmem_max when privileged; otherwise take what SO_RCVBUF allows.
    if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &receive_buffer_bytes,
                     sizeof receive_buffer_bytes) != 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof receive_buffer_bytes);
    }
  }
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const std::string why = std::strerror(errno);
    close_fd();
    throw std::runtime_error("UDP bind to " + local_ip + ":" + std::to_string(local_port) +
                             ": " + why);
  }
  sockaddr_in bound{};
  socklen_t len = sizeof bound;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  local_port_ = ntohs(bound.sin_port);
}

UdpSocket::~UdpSocket() { close_fd(); }

UdpSocket::UdpSocket(UdpSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      local_port_(other.local_port_),
      buffer_(std::move(other.buffer_)) {}

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    close_fd();
    fd_ = std::exchange(other.fd_, -1);
    local_port_ = other.local_port_;
    buffer_ = std::move(other.buffer_);
  }
  return *this;
}

void UdpSocket::close_fd() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool UdpSocket::send_to(const Endpoint& to, std::string_view bytes) {
  const sockaddr_in a = to_sockaddr(to);
  const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0,
                             reinterpret_cast<const sockaddr*>(&a), sizeof a);
  return n == static_cast<ssize_t>(bytes.size());
}

std::optional<Datagram> UdpSocket::receive() {
  sockaddr_in from{};
  socklen_t len = sizeof from;
  const ssize_t n = ::recvfrom(fd_, buffer_.data(), buffer_.size(), 0,
                               reinterpret_cast<sockaddr*>(&from), &len);
  if (n < 0) return std::nullopt;  // EAGAIN (nothing waiting) or a transient error
  char ip[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &from.sin_addr, ip, sizeof ip);
  return Datagram{std::string(buffer_.data(), static_cast<size_t>(n)), {ip, ntohs(from.sin_port)}};
}

bool UdpSocket::wait_readable(int timeout_ms) const {
  pollfd p{fd_, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) > 0 && (p.revents & POLLIN);
}

}  // namespace shelfcross::tello
