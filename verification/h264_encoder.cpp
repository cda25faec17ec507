#include "verification/h264_encoder.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
}

namespace shelfcross::verification {
namespace {

// FFmpeg's log stays quiet (as the decoder's does): the callers report what matters.
void quiet_ffmpeg() {
  static const bool once = [] {
    av_log_set_level(AV_LOG_FATAL);
    return true;
  }();
  (void)once;
}

}  // namespace

struct H264Encoder::Impl {
  AVCodecContext* ctx = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  cv::Mat i420;  ///< the picture as planar YUV 4:2:0: Y rows, then U, then V (OpenCV's I420)
  int64_t pts = 0;

  ~Impl() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&ctx);
  }
};

H264Encoder::H264Encoder(int width_px, int height_px, int fps, int key_interval, int crf, int slices)
    : impl_(std::make_unique<Impl>()) {
  quiet_ffmpeg();
  if (width_px < 2 || height_px < 2 || width_px % 2 || height_px % 2) {
    throw std::invalid_argument("H264Encoder: 4:2:0 needs an even width and height, got " + std::to_string(width_px) +
                                " x " + std::to_string(height_px));
  }
  if (slices < 1 || slices > (height_px + 15) / 16) {
    throw std::invalid_argument("H264Encoder: slices must be 1.." + std::to_string((height_px + 15) / 16) +
                                " (macroblock rows), got " + std::to_string(slices));
  }
  const AVCodec* codec = avcodec_find_encoder_by_name("libx264");
  if (!codec) throw std::runtime_error("libavcodec has no libx264 encoder");
  AVCodecContext* c = impl_->ctx = avcodec_alloc_context3(codec);
  if (!c) throw std::runtime_error("H.264 encoder: out of memory");
  c->width = width_px;
  c->height = height_px;
  c->time_base = AVRational{1, fps};
  c->framerate = AVRational{fps, 1};
  c->pix_fmt = AV_PIX_FMT_YUV420P;
  c->gop_size = key_interval;
  c->max_b_frames = 0;
  c->thread_count = 1;
  av_opt_set(c->priv_data, "preset", "ultrafast", 0);
  av_opt_set(c->priv_data, "tune", "zerolatency", 0);
  av_opt_set(c->priv_data, "crf", std::to_string(crf).c_str(), 0);
  // Annex-B start codes, SPS/PPS before every key frame, no scene-cut key frames.
  const std::string params = "repeat-headers=1:annexb=1:scenecut=0:slices=" + std::to_string(slices);
  av_opt_set(c->priv_data, "x264-params", params.c_str(), 0);
  if (avcodec_open2(c, codec, nullptr) < 0) throw std::runtime_error("cannot open libx264");
  impl_->frame = av_frame_alloc();
  impl_->packet = av_packet_alloc();
  impl_->frame->format = AV_PIX_FMT_YUV420P;
  impl_->frame->width = width_px;
  impl_->frame->height = height_px;
  if (av_frame_get_buffer(impl_->frame, 0) < 0) throw std::runtime_error("H.264 encoder: out of memory");
}

H264Encoder::~H264Encoder() = default;

std::string H264Encoder::encode(const cv::Mat& bgr, bool force_key_frame) {
  Impl& m = *impl_;
  if (bgr.type() != CV_8UC3 || bgr.cols != m.ctx->width || bgr.rows != m.ctx->height) {
    throw std::invalid_argument("H264Encoder::encode: expected a BGR image of the encoder's size");
  }
  av_frame_make_writable(m.frame);
  // BGR -> YUV 4:2:0 (ITU-R BT.601, studio range, as libswscale's default) with OpenCV's
  // vectorised conversion: libswscale has no unscaled fast path from BGR24, and its generic
  // scaler cost about a third as much as the encoding itself. Then plane by plane into the
  // encoder's frame (its rows may be padded).
  cv::cvtColor(bgr, m.i420, cv::COLOR_BGR2YUV_I420);
  const int w = bgr.cols, h = bgr.rows;
  const std::uint8_t* y = m.i420.data;
  const std::uint8_t* u = y + static_cast<std::size_t>(w) * h;
  const std::uint8_t* v = u + static_cast<std::size_t>(w / 2) * (h / 2);
  for (int r = 0; r < h; ++r) std::memcpy(m.frame->data[0] + r * m.frame->linesize[0], y + r * w, w);
  for (int r = 0; r < h / 2; ++r) {
    std::memcpy(m.frame->data[1] + r * m.frame->linesize[1], u + r * (w / 2), w / 2);
    std::memcpy(m.frame->data[2] + r * m.frame->linesize[2], v + r * (w / 2), w / 2);
  }
  m.frame->pts = m.pts++;
  m.frame->pict_type = force_key_frame ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  m.frame->key_frame = force_key_frame ? 1 : 0;
  if (avcodec_send_frame(m.ctx, m.frame) < 0) throw std::runtime_error("libx264 refused a frame");
  std::string out;
  while (avcodec_receive_packet(m.ctx, m.packet) == 0) {
    out.append(reinterpret_cast<const char*>(m.packet->data), static_cast<size_t>(m.packet->size));
    av_packet_unref(m.packet);
  }
  return out;
}

}  // namespace shelfcross::verification
