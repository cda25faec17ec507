#pragma once
// The simulated Tello's video encoder: libx264 through FFmpeg's libavcodec (Debian), making a
// Tello-like H.264 stream for the emulator, the co-simulation, and the tests and benchmarks of
// the video receiver. The drone's side of the link: it lives in verification/ so that
// `tello_pilot` never links it (the receiver's decoder is flight_sw/tello/h264_decoder.hpp;
// the datagram framing both sides share is sdk/video_framing.hpp).

#include <memory>
#include <string>

#include <opencv2/core/mat.hpp>

namespace shelfcross::verification {

/// libx264 through libavcodec: ultrafast preset, zerolatency tune, one thread, no B-frames,
/// a constant quantiser `qp` for every frame, Annex-B with SPS/PPS repeated before every key
/// frame (as the Tello sends), `slices` slices per picture (x264 `slices`: bands of whole
/// macroblock rows; 1: one slice per picture).
class H264Encoder {
 public:
  /// The Tello's stream: about 3 Mbit/s at 30 frames/s, key frames about 35 kB, others about
  /// 10 kB (docs/tello_sdk.md, "Video"). On rendered frames of the paper's shelf with the
  /// default sensor noise, qp 25 gives 2.9 Mbit/s, key frames 42 kB and others 11 kB
  /// (BM_EncodeRendered, bench/README.md); 24 and 26 miss the bitrate by more.
  static constexpr int kTelloQp = 25;

  /// Throws std::runtime_error when libavcodec has no libx264 encoder, std::invalid_argument
  /// for an odd size, qp outside 0..51 or slices outside 1..(macroblock rows).
  H264Encoder(int width_px, int height_px, int fps = 30, int key_interval = 30, int qp = kTelloQp, int slices = 1);
  ~H264Encoder();
  H264Encoder(const H264Encoder&) = delete;
  H264Encoder& operator=(const H264Encoder&) = delete;

  /// One BGR frame (CV_8UC3, the encoder's size) in, one access unit out (Annex-B bytes).
  std::string encode(const cv::Mat& bgr, bool force_key_frame = false);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::verification
