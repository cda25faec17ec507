#pragma once
// The Tello's video: raw H.264 Annex-B on UDP port 11111, each frame cut into 1460-byte
// datagrams with a shorter last one (docs/tello_sdk.md). A receiver thread reassembles the
// datagrams of one frame (up to the first short datagram that ends more than parameter sets), decodes them at once with the
// low-delay H264Decoder, converts the picture to BGR and puts it in a single-slot mailbox:
// a newer frame replaces one not yet taken, so the taker always gets the newest frame and
// never a backlog.
//
// Damage: a lost datagram corrupts pictures until the next key frame (docs/tello_sdk.md). Signs
// of damage: a decoder error or concealment flag, a frame that does not begin with a start
// code (its first datagram was lost), a frame that decodes to no picture, an over-long frame,
// a frame whose short last datagram was lost (found when the next frame's first datagram
// arrives: a start code and an SPS, PPS, SEI, delimiter or a slice beginning at macroblock 0;
// the Tello starts every frame in a datagram of its own). What happens then depends on
// VideoReceiverConfig::damaged:
//   conceal (default): every picture the decoder outputs after the first clean key frame is
//     handed over, damaged ones as libavcodec's error concealment filled them in (lost
//     macroblocks copied from the previous picture along guessed motion; h264_decoder.hpp), and
//     marked: VideoFrame::damaged is true from the first sign of damage until a key frame
//     decodes cleanly. What a real Tello user sees: smeared bands, not a frozen picture.
//   discard: nothing is handed over from the first sign of damage until a key frame decodes
//     cleanly (at a few percent of datagram loss almost nothing gets through: a 1 s group of
//     pictures is ~100 datagrams).
// Nothing is handed over before the first key frame (conceal: the first that gives a picture,
// marked damaged if it is; discard: the first clean one).
//
// Datagrams from anyone but drone_ip (and source_port when set) are dropped and counted.
// Times come from the Clock (its now_ns() is called from the receiver thread).
//
// Its parts: frame_assembler.hpp (datagrams -> frames), stream_damage.hpp (which frames are
// damaged and handed over, and where their damage lies), frame_mailbox.hpp (the single-slot
// mailbox, VideoFrame and the counters).

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/frame_assembler.hpp"
#include "flight_sw/tello/frame_mailbox.hpp"
#include "flight_sw/tello/udp_socket.hpp"
#include "sdk/video_framing.hpp"

namespace shelfcross::tello {

enum class DamagedFrames { conceal, discard };

struct VideoReceiverConfig {
  std::string drone_ip = "192.168.10.1";
  std::uint16_t source_port = 0;  ///< 0: any port of drone_ip
  std::string local_ip = "0.0.0.0";
  std::uint16_t local_port = 11111;  ///< 0: ephemeral (tests)
  size_t datagram_size = sdk::kVideoDatagramBytes;  ///< a datagram shorter than this ends a frame
  size_t max_frame_bytes = 1 << 20;  ///< a frame growing past this is dropped (lost frame end)
  int receive_buffer_bytes = 4 << 20;
  DamagedFrames damaged = DamagedFrames::conceal;  ///< see the header comment
  /// true: a receiver thread reads and decodes as datagrams arrive (tello_pilot). false: no
  /// thread; the owner calls service(), which reads and decodes what has arrived, in its own
  /// thread (the co-simulation: deterministic, decoding charged to the run).
  bool threaded = true;
};

class VideoReceiver {
 public:
  /// Binds the video port and starts the receiver thread. Throws std::runtime_error (port
  /// busy, no H.264 decoder) or std::invalid_argument (bad address).
  VideoReceiver(VideoReceiverConfig config, const Clock& clock);
  /// The same receiver reading the caller's channel (config's local port is not used).
  VideoReceiver(VideoReceiverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> channel);
  ~VideoReceiver();  ///< stops and joins the thread
  VideoReceiver(const VideoReceiver&) = delete;
  VideoReceiver& operator=(const VideoReceiver&) = delete;

  /// Unthreaded receivers: reads every datagram that has arrived, decoding each frame as it
  /// completes. A threaded receiver does this on its thread; there it does nothing.
  void service();
  /// The newest frame not yet taken (the mailbox empties), or nothing.
  std::optional<VideoFrame> take_latest() { return mailbox_.take(); }
  /// An eventfd that is readable while a frame waits in the mailbox (for poll()).
  int notify_fd() const { return mailbox_.notify_fd(); }
  VideoStats stats() const { return mailbox_.stats(); }
  /// When the newest frame was handed over; nothing before the first.
  std::optional<TimeNs> last_frame_ns() const { return mailbox_.last_frame_ns(); }
  /// True when no frame was handed over for longer than `threshold_ns` (counted from the
  /// receiver's start before the first frame).
  bool stalled(TimeNs threshold_ns) const { return mailbox_.stalled(threshold_ns); }
  std::uint16_t local_port() const { return local_port_; }

 private:
  struct ThreadState;
  void run();
  void on_datagram(const Datagram& d);
  /// Decodes a reassembled frame, judges its damage and hands it over or discards it.
  void finish_frame(AssembledFrame f);

  VideoReceiverConfig config_;
  const Clock& clock_;
  FrameMailbox mailbox_;
  std::uint16_t local_port_ = 0;
  int stop_fd_ = -1;
  std::atomic<bool> stop_{false};
  std::unique_ptr<ThreadState> thread_state_;  ///< the receiver thread's only
  std::thread thread_;
};

}  // namespace shelfcross::tello
