// The video receiver's datagram input (flight_sw/tello/video_receiver.hpp): the input is a
// sequence of datagrams, each a 2-byte big-endian header and its bytes. The header's top bit
// says the datagram comes from a foreign sender; its other 15 bits are the length (cut to what
// is left). An unthreaded receiver on a MemoryChannel takes them one at a time, 33 ms apart on
// a ManualClock, reassembling and decoding as the co-simulation does. Whatever arrives, it
// must not crash, and what it hands over is a BGR picture.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/datagram_channel.hpp"
#include "flight_sw/tello/video_receiver.hpp"

using namespace shelfcross;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  tello::ManualClock clock(1'000'000'000);
  tello::VideoReceiverConfig config;
  config.threaded = false;
  config.local_port = 0;
  config.max_frame_bytes = 64 << 10;  // small enough that the fuzzer reaches the oversize path
  config.damaged = (size % 2) ? tello::DamagedFrames::discard : tello::DamagedFrames::conceal;
  auto owned = std::make_unique<tello::MemoryChannel>(tello::Endpoint{"127.0.0.1", 11111});
  tello::MemoryChannel& channel = *owned;
  tello::VideoReceiver receiver(config, clock, std::move(owned));
  const tello::Endpoint drone{config.drone_ip, 62512};
  const tello::Endpoint stranger{"10.0.0.7", 62512};

  std::size_t at = 0;
  while (at + 2 <= size) {
    const unsigned header = (unsigned(data[at]) << 8) | data[at + 1];
    at += 2;
    const std::size_t n = std::min<std::size_t>(header & 0x7fffu, size - at);
    channel.deliver({std::string(reinterpret_cast<const char*>(data + at), n), (header & 0x8000u) ? stranger : drone});
    at += n;
    clock.advance(33'000'000);
    receiver.service();
    if (auto frame = receiver.take_latest()) {
      if (frame->bgr.empty() || frame->bgr.type() != CV_8UC3) {
        std::fprintf(stderr, "video receiver: handed over a frame that is not a BGR picture\n");
        std::abort();
      }
    }
  }
  const tello::VideoStats stats = receiver.stats();
  if (stats.handed > stats.pictures || stats.taken > stats.handed) {
    std::fprintf(stderr, "video receiver: inconsistent stats: %s\n", stats.text().c_str());
    std::abort();
  }
  return 0;
}
