#pragma once
// H.264 through FFmpeg's libavcodec (Debian): the low-delay decoder the video receiver uses.
// The drone's side (the libx264 encoder that makes a Tello-like stream) is
// verification/world/h264_encoder.hpp; the datagram framing both sides share is
// sdk/video_framing.hpp.

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "flight_sw/tello/picture_damage.hpp"

namespace shelfcross::tello {

/// Sets FFmpeg's process-wide log level to fatal messages only, once (thread-safe; later calls
/// do nothing). The decoder and the simulated Tello's encoder both call it: their callers
/// report what matters (damage counts, errors) themselves.
void quiet_ffmpeg();

/// What decoding one access unit gave.
struct DecodeResult {
  int pictures = 0;       ///< pictures completed by these bytes
  bool error = false;     ///< the decoder refused the bytes or reported damage in a picture
  bool key_frame = false; ///< the last picture is an intra (IDR/I) picture
  bool clean = false;     ///< the last picture was decoded without reported damage
  bool concealed = false; ///< the last picture has macroblocks filled in by error concealment
  /// The last picture's inter blocks, from libavcodec's exported motion vectors
  /// (AV_CODEC_EXPORT_DATA_MVS): where each lands and where it comes from (picture_damage.hpp).
  std::vector<BlockMotion> motion;
  int refs = 1;           ///< reference pictures the stream's SPS allows (at least 1)
  /// Where libavcodec's slice decoder failed in these bytes (macroblock indices, raster order:
  /// its "error while decoding MB x y" report) and how many macroblocks its error resilience
  /// concealed in the last picture ("concealing ... MV errors"; 0 when it concealed nothing).
  std::vector<int> error_mbs;
  int concealed_mbs = 0;
};

/// av_parser_parse2 with the h264 parser over access units (the receiver hands one
/// reassembled frame at a time, so the parser runs with PARSER_FLAG_COMPLETE_FRAMES and never
/// holds a frame back waiting for the next start code), then the h264 decoder with
/// AV_CODEC_FLAG_LOW_DELAY, AV_CODEC_FLAG2_FAST, one thread (no frame threads: no frame of
/// delay) and no reordering delay: each access unit's picture comes out as it goes in.
///
/// Damage: libavcodec's error resilience is on (the h264 decoder's `enable_er` default, which
/// needs no slice threads) with error_concealment = guess_mvs | deblock | favor_inter: the
/// macroblocks of a lost or undecodable stretch are filled from the previous picture moved by
/// the motion vectors guessed from their neighbours (favor_inter: also in intra pictures,
/// where the default would interpolate spatially), and AV_CODEC_FLAG_OUTPUT_CORRUPT outputs
/// such pictures (frame->decode_error_flags has FF_DECODE_ERROR_CONCEALMENT_ACTIVE) instead of
/// holding them back. Whether to use them is the caller's choice (DecodeResult::concealed).
class H264Decoder {
 public:
  H264Decoder();  ///< throws std::runtime_error when libavcodec has no h264 decoder
  ~H264Decoder();
  H264Decoder(const H264Decoder&) = delete;
  H264Decoder& operator=(const H264Decoder&) = delete;

  DecodeResult decode(std::string_view access_unit);
  /// The last decoded picture as BGR (CV_8UC3) through libswscale; false when none.
  bool latest_bgr(cv::Mat& bgr);
  /// The last decoded picture's size in pixels; false when none.
  bool latest_size(int& width_px, int& height_px) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Peak signal-to-noise ratio of two 8-bit images of one size and type, dB (inf if equal).
/// Throws std::invalid_argument when they differ in size or type.
double psnr_db(const cv::Mat& a, const cv::Mat& b);

}  // namespace shelfcross::tello
