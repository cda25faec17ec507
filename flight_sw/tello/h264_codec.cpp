#include "flight_sw/tello/h264_codec.hpp"

#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace shelfcross::tello {
namespace {

// FFmpeg's decoders print every damaged macroblock; the receiver counts errors itself.
void quiet_ffmpeg() {
  static const bool once = [] {
    av_log_set_level(AV_LOG_FATAL);
    return true;
  }();
  (void)once;
}

// Start code positions: (offset of the first byte after 00 00 01, start of the start code).
struct Nal {
  size_t code_begin;  ///< first byte of the start code (00 00 01 or 00 00 00 01)
  size_t payload;     ///< first byte of the NAL header
};

std::vector<Nal> find_nals(std::string_view s) {
  std::vector<Nal> nals;
  for (size_t i = 0; i + 3 <= s.size(); ++i) {
    if (s[i] == 0 && s[i + 1] == 0 && s[i + 2] == 1) {
      const size_t begin = (i > 0 && s[i - 1] == 0) ? i - 1 : i;
      nals.push_back({begin, i + 3});
      i += 2;
    }
  }
  return nals;
}

}  // namespace

// ---- Decoder ----

struct H264Decoder::Impl {
  AVCodecParserContext* parser = nullptr;
  AVCodecContext* ctx = nullptr;
  AVPacket* packet = nullptr;
  AVFrame* frame = nullptr;   // receive buffer
  AVFrame* latest = nullptr;  // the last decoded picture
  bool have_latest = false;
  SwsContext* sws = nullptr;

  ~Impl() {
    sws_freeContext(sws);
    av_frame_free(&latest);
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&ctx);
    if (parser) av_parser_close(parser);
  }

  void send(DecodeResult& r) {
    if (avcodec_send_packet(ctx, packet) < 0) r.error = true;
    for (;;) {
      const int rc = avcodec_receive_frame(ctx, frame);
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) break;
      if (rc < 0) {
        r.error = true;
        break;
      }
      ++r.pictures;
      const bool damaged = frame->decode_error_flags != 0 || (frame->flags & AV_FRAME_FLAG_CORRUPT);
      if (damaged) r.error = true;
      r.clean = !damaged;
      r.concealed = damaged;
      r.key_frame = frame->key_frame || frame->pict_type == AV_PICTURE_TYPE_I;
      av_frame_unref(latest);
      av_frame_move_ref(latest, frame);
      have_latest = true;
    }
  }
};

H264Decoder::H264Decoder() : impl_(std::make_unique<Impl>()) {
  quiet_ffmpeg();
  const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
  if (!codec) throw std::runtime_error("libavcodec has no H.264 decoder");
  impl_->parser = av_parser_init(AV_CODEC_ID_H264);
  impl_->ctx = avcodec_alloc_context3(codec);
  impl_->packet = av_packet_alloc();
  impl_->frame = av_frame_alloc();
  impl_->latest = av_frame_alloc();
  if (!impl_->parser || !impl_->ctx || !impl_->packet || !impl_->frame || !impl_->latest) {
    throw std::runtime_error("H.264 decoder: out of memory");
  }
  // Each call hands a whole access unit: output it now, not when the next start code shows.
  impl_->parser->flags |= PARSER_FLAG_COMPLETE_FRAMES;
  AVCodecContext* c = impl_->ctx;
  c->flags |= AV_CODEC_FLAG_LOW_DELAY;  // output each picture at once, no reorder buffer
  c->flags2 |= AV_CODEC_FLAG2_FAST;
  c->thread_count = 1;                  // frame threads would add a frame of delay per thread
  c->thread_type = 0;
  c->has_b_frames = 0;
  // Damaged pictures: concealed from the previous picture (see the header) and output.
  c->flags |= AV_CODEC_FLAG_OUTPUT_CORRUPT;
  c->error_concealment = FF_EC_GUESS_MVS | FF_EC_DEBLOCK | FF_EC_FAVOR_INTER;
  if (avcodec_open2(c, codec, nullptr) < 0) throw std::runtime_error("cannot open the H.264 decoder");
}

H264Decoder::~H264Decoder() = default;

DecodeResult H264Decoder::decode(std::string_view au) {
  DecodeResult r;
  const auto* data = reinterpret_cast<const uint8_t*>(au.data());
  int size = static_cast<int>(au.size());
  while (size > 0) {
    uint8_t* out = nullptr;
    int out_size = 0;
    const int used = av_parser_parse2(impl_->parser, impl_->ctx, &out, &out_size, data, size,
                                      AV_NOPTS_VALUE, AV_NOPTS_VALUE, 0);
    if (used < 0) {
      r.error = true;
      break;
    }
    data += used;
    size -= used;
    if (out_size > 0) {
      impl_->packet->data = out;
      impl_->packet->size = out_size;
      impl_->send(r);
    }
    if (used == 0 && out_size == 0) break;  // no progress
  }
  return r;
}

bool H264Decoder::latest_bgr(cv::Mat& bgr) {
  if (!impl_->have_latest) return false;
  const AVFrame* f = impl_->latest;
  impl_->sws = sws_getCachedContext(impl_->sws, f->width, f->height,
                                    static_cast<AVPixelFormat>(f->format), f->width, f->height,
                                    AV_PIX_FMT_BGR24, SWS_POINT, nullptr, nullptr, nullptr);
  if (!impl_->sws) return false;
  bgr.create(f->height, f->width, CV_8UC3);
  uint8_t* dst[4] = {bgr.data, nullptr, nullptr, nullptr};
  int dst_stride[4] = {static_cast<int>(bgr.step[0]), 0, 0, 0};
  sws_scale(impl_->sws, f->data, f->linesize, 0, f->height, dst, dst_stride);
  return true;
}

// ---- Encoder ----

struct H264Encoder::Impl {
  AVCodecContext* ctx = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* sws = nullptr;
  int64_t pts = 0;

  ~Impl() {
    sws_freeContext(sws);
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&ctx);
  }
};

H264Encoder::H264Encoder(int width_px, int height_px, int fps, int key_interval, int crf, int slices)
    : impl_(std::make_unique<Impl>()) {
  quiet_ffmpeg();
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
  m.sws = sws_getCachedContext(m.sws, bgr.cols, bgr.rows, AV_PIX_FMT_BGR24, bgr.cols, bgr.rows,
                               AV_PIX_FMT_YUV420P, SWS_POINT, nullptr, nullptr, nullptr);
  const uint8_t* src[4] = {bgr.data, nullptr, nullptr, nullptr};
  const int src_stride[4] = {static_cast<int>(bgr.step[0]), 0, 0, 0};
  sws_scale(m.sws, src, src_stride, 0, bgr.rows, m.frame->data, m.frame->linesize);
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

// ---- Stream helpers ----

std::vector<int> nal_unit_types(std::string_view s) {
  std::vector<int> types;
  for (const Nal& n : find_nals(s)) {
    if (n.payload < s.size()) types.push_back(static_cast<unsigned char>(s[n.payload]) & 0x1f);
  }
  return types;
}

std::vector<std::string> tello_datagrams(std::string_view au, size_t datagram_size) {
  assert(datagram_size >= 2);
  std::vector<std::string> out;
  const std::vector<Nal> nals = find_nals(au);
  size_t rest = 0;
  // Leading parameter sets (SPS 7, PPS 8, access unit delimiter 9): one datagram each.
  for (size_t i = 0; i < nals.size(); ++i) {
    const int type = nals[i].payload < au.size() ? (static_cast<unsigned char>(au[nals[i].payload]) & 0x1f) : 0;
    if (type != 7 && type != 8 && type != 9) break;
    const size_t end = i + 1 < nals.size() ? nals[i + 1].code_begin : au.size();
    if (end - nals[i].code_begin >= datagram_size) break;  // too big to stand alone as "short"
    out.emplace_back(au.substr(nals[i].code_begin, end - nals[i].code_begin));
    rest = end;
  }
  std::string_view body = au.substr(rest);
  while (body.size() > datagram_size) {
    out.emplace_back(body.substr(0, datagram_size));
    body.remove_prefix(datagram_size);
  }
  if (body.size() == datagram_size) {  // keep the last datagram short
    out.emplace_back(body.substr(0, datagram_size - 1));
    body.remove_prefix(datagram_size - 1);
  }
  if (!body.empty()) out.emplace_back(body);
  return out;
}

double psnr_db(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) {
    throw std::invalid_argument("psnr_db: images differ in size or type");
  }
  const double norm = cv::norm(a, b, cv::NORM_L2SQR);
  if (norm == 0.0) return std::numeric_limits<double>::infinity();
  const double mse = norm / static_cast<double>(a.total() * a.channels());
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace shelfcross::tello
