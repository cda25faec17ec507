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

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/picture_damage.hpp"
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

/// One decoded frame as handed over.
struct VideoFrame {
  TimeNs t_ns = 0;          ///< arrival of the frame's last datagram
  TimeNs handed_ns = 0;     ///< when it was put in the mailbox (decoded and converted)
  std::int64_t index = 0;   ///< 0, 1, 2, ... over handed-over frames; a gap = frames replaced
  bool damaged = false;     ///< error-concealed: damage since the last clean key frame
  /// Key frames decoded before and with this frame: frames of one group of pictures share
  /// it (and their damage: it lasts until the next key frame), frames of two groups do not.
  std::int64_t key_group = 0;
  /// Frames with a sign of damage since the last key frame, this one and a damaged key frame
  /// included: 0 for a clean frame of a clean group; each lost datagram adds a band (two
  /// slices or so) concealed from the previous picture, and the bands add up until the next
  /// key frame. A measure of how much of the picture is guesswork.
  int damage_events = 0;
  /// Where the damage may lie (CameraFrame::damaged_rows; picture_damage.hpp): empty for a
  /// clean frame of a clean group, and for a damaged one whose damage has left the picture.
  std::vector<RowSpan> damaged_rows;
  cv::Mat bgr;              ///< CV_8UC3
};

struct VideoStats {
  std::int64_t datagrams = 0;
  std::int64_t bytes = 0;
  std::int64_t foreign_datagrams = 0;
  std::int64_t frames_received = 0;   ///< reassembled frames (access units) decoded
  std::int64_t oversize_frames = 0;
  std::int64_t pictures = 0;          ///< pictures the decoder produced
  std::int64_t damaged = 0;           ///< frames with a sign of damage (see header comment)
  std::int64_t discarded = 0;         ///< pictures not handed over (damaged or awaiting a key frame)
  std::int64_t truncated = 0;         ///< frames whose short last datagram was lost
  std::int64_t handed = 0;            ///< frames put in the mailbox
  std::int64_t handed_damaged = 0;    ///< of which marked damaged (concealed)
  std::int64_t replaced = 0;          ///< frames replaced in the mailbox before being taken
  std::int64_t taken = 0;
  std::string text() const;           ///< "name=value ..." on one line
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
  std::optional<VideoFrame> take_latest();
  /// An eventfd that is readable while a frame waits in the mailbox (for poll()).
  int notify_fd() const { return notify_fd_; }
  VideoStats stats() const;
  /// When the newest frame was handed over; nothing before the first.
  std::optional<TimeNs> last_frame_ns() const;
  /// True when no frame was handed over for longer than `threshold_ns` (counted from the
  /// receiver's start before the first frame).
  bool stalled(TimeNs threshold_ns) const;
  std::uint16_t local_port() const { return local_port_; }

 private:
  void run();
  void on_datagram(const Datagram& d);
  void finish_frame(TimeNs t_ns, bool lost_end);

  VideoReceiverConfig config_;
  const Clock& clock_;
  TimeNs started_ns_;
  std::uint16_t local_port_ = 0;
  int notify_fd_ = -1;
  int stop_fd_ = -1;
  std::atomic<bool> stop_{false};

  // Receiver thread only.
  std::string frame_bytes_;
  bool frame_overflow_ = false;
  TimeNs last_datagram_ns_ = 0;     ///< arrival of the newest datagram of the frame gathered
  bool synced_ = false;             ///< a key frame decoded since the start (discard: a clean one)
  bool damaged_since_key_ = false;  ///< a sign of damage since the last clean key frame
  std::int64_t key_frames_ = 0;     ///< key frames decoded (damaged or not)
  int damage_events_ = 0;           ///< damaged frames since the last key frame (see VideoFrame)
  std::vector<std::size_t> datagram_ends_;  ///< where each datagram of the frame gathered ended
  std::unique_ptr<PictureDamage> picture_damage_;  ///< sized by the first picture
  int picture_width_px_ = 0, picture_height_px_ = 0;
  bool picture_lost_ = false;  ///< an access unit gave no picture: the next one's damage is unplaced
  struct ThreadState;
  std::unique_ptr<ThreadState> thread_state_;

  mutable std::mutex mutex_;  // guards the mailbox, stats and last_frame_ns_
  std::optional<VideoFrame> mailbox_;
  VideoStats stats_;
  std::optional<TimeNs> last_frame_ns_;
  std::int64_t next_index_ = 0;

  std::thread thread_;
};

}  // namespace shelfcross::tello
