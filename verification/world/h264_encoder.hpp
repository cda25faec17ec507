#pragma once
// The simulated Tello's video encoder: libx264 (or, for benchmarks, NVIDIA's hardware
// encoder) through FFmpeg's libavcodec (Debian), making a Tello-like H.264 stream for the
// emulator, the co-simulation, and the tests and benchmarks of the video receiver. The
// drone's side of the link: it lives in verification/ so that `tello_pilot` never links it
// (the receiver's decoder is flight_sw/tello/h264_decoder.hpp; the datagram framing both
// sides share is sdk/video_framing.hpp).

#include <memory>
#include <string>

#include <opencv2/core/mat.hpp>

namespace shelfcross::verification {

/// A Tello-like H.264 encoder through libavcodec: no B-frames, a constant quantiser `qp` for
/// every frame type, Annex-B with SPS/PPS repeated before every key frame (as the Tello sends),
/// `slices` slices per picture (bands of whole macroblock rows; 1: one slice per picture), a
/// key frame every `key_interval` frames and wherever encode() forces one.
class H264Encoder {
 public:
  /// Which encoder makes the stream.
  ///  - Libx264: FFmpeg's `libx264` on the CPU, ultrafast preset, zerolatency tune, one thread,
  ///    x264's own `qp`, `ipratio` 1, `repeat-headers`, `annexb`, no scene-cut key frames. The
  ///    emulator, the co-simulation and every certified run use it (the default).
  ///  - Nvenc: FFmpeg's `h264_nvenc` (NVIDIA's hardware encoder; needs an NVIDIA GPU and its
  ///    driver, whose libcuda.so.1 and libnvidia-encode.so.1 libavcodec loads when the encoder
  ///    opens): `rc` constqp with `init_qpI` = `init_qpP` = `init_qpB` = qp (FFmpeg's `qp`
  ///    alone would give key frames qp x 0.8), the fastest preset `p1`, ultra-low-latency tune
  ///    `ull`, `zerolatency` 1, `delay` 0 (each frame's packet out of the call that sends it),
  ///    `forced-idr` 1 (a forced key frame is an IDR, not an I picture), no global header (so
  ///    NVENC repeats SPS/PPS before every IDR). For the benchmarks that ask whether it can
  ///    stand in for libx264 (bench/README.md); nothing else selects it.
  enum class Backend { Libx264, Nvenc };

  /// The Tello's stream: about 3 Mbit/s at 30 frames/s, key frames about 35 kB, others about
  /// 10 kB (docs/tello_sdk.md, "Video"). On rendered frames of the paper's shelf with the
  /// default sensor noise, qp 25 gives 2.9 Mbit/s, key frames 42 kB and others 11 kB
  /// (BM_EncodeRendered, bench/README.md); 24 and 26 miss the bitrate by more.
  static constexpr int kTelloQp = 25;

  /// Throws std::invalid_argument for an odd size, qp outside 0..51 or slices outside
  /// 1..(macroblock rows); std::runtime_error when libavcodec lacks the backend's encoder or
  /// cannot open it (for Nvenc: no NVIDIA GPU or driver; the message names NVENC and gives
  /// libavcodec's reason).
  H264Encoder(int width_px, int height_px, int fps = 30, int key_interval = 30, int qp = kTelloQp, int slices = 1,
              Backend backend = Backend::Libx264);
  ~H264Encoder();
  H264Encoder(const H264Encoder&) = delete;
  H264Encoder& operator=(const H264Encoder&) = delete;

  /// One BGR frame (CV_8UC3, the encoder's size) in, one access unit out (Annex-B bytes).
  /// Throws std::invalid_argument for another type or size, std::runtime_error when the
  /// encoder refuses the frame or gives no access unit for it.
  std::string encode(const cv::Mat& bgr, bool force_key_frame = false);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::verification
