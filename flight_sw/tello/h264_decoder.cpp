#include "flight_sw/tello/h264_decoder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/motion_vector.h>
#include <libswscale/swscale.h>
}

namespace shelfcross::tello {

namespace {

// What libavcodec reports of a decode in progress, by codec context: where a slice failed and
// how many macroblocks error resilience concealed. libavcodec says this only in its log, so
// the process-wide log callback routes the messages of the contexts registered here to their
// decoder (it runs on the thread that called the decode: the decoder has no threads of its
// own); every other message goes to FFmpeg's default callback, which the level set below
// keeps quiet.
struct DecodeReports {
  std::vector<std::pair<int, int>> error_xy;  ///< macroblock column, row
  int concealed_mbs = 0;
};

std::mutex reports_mutex;
std::map<const void*, DecodeReports*>& report_registry() {
  static std::map<const void*, DecodeReports*> registry;
  return registry;
}

void log_callback(void* avcl, int level, const char* fmt, va_list args) {
  DecodeReports* reports = nullptr;
  {
    std::lock_guard lock(reports_mutex);
    const auto& registry = report_registry();
    const auto it = registry.find(avcl);
    if (it != registry.end()) reports = it->second;
  }
  if (!reports) {
    av_log_default_callback(avcl, level, fmt, args);
    return;
  }
  char line[256];
  va_list copy;
  va_copy(copy, args);
  std::vsnprintf(line, sizeof line, fmt, copy);
  va_end(copy);
  int x = 0, y = 0, dc = 0, ac = 0, mv = 0;
  if (std::sscanf(line, "error while decoding MB %d %d", &x, &y) == 2) {
    reports->error_xy.push_back({x, y});
  } else if (std::sscanf(line, "concealing %d DC, %d AC, %d MV errors", &dc, &ac, &mv) == 3) {
    reports->concealed_mbs = std::max({dc, ac, mv});
  }
}

}  // namespace

// FFmpeg's decoders print every damaged macroblock; the receiver counts errors itself.
void quiet_ffmpeg() {
  static const bool once = [] {
    av_log_set_level(AV_LOG_FATAL);
    av_log_set_callback(log_callback);
    return true;
  }();
  (void)once;
}

// ---- Decoder ----

struct H264Decoder::Impl {
  AVCodecParserContext* parser = nullptr;
  AVCodecContext* ctx = nullptr;
  AVPacket* packet = nullptr;
  AVFrame* frame = nullptr;   // receive buffer
  AVFrame* latest = nullptr;  // the last decoded picture
  bool have_latest = false;
  DecodeReports reports;  // registered for ctx while it lives
  SwsContext* sws = nullptr;
  // The access unit's bytes followed by AV_INPUT_BUFFER_PADDING_SIZE zero bytes: libavcodec's
  // parser and bit readers read up to that far past the end of their input (avcodec.h,
  // av_parser_parse2: "the full buffer size is assumed to be buf_size +
  // AV_INPUT_BUFFER_PADDING_SIZE"); without them a damaged frame ending at a page boundary
  // faults (the video_receiver fuzzer found it).
  std::vector<uint8_t> padded;

  ~Impl() {
    {
      std::lock_guard lock(reports_mutex);
      report_registry().erase(ctx);
    }
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
      r.refs = std::max(1, ctx->refs);
      r.motion.clear();
      if (const AVFrameSideData* sd = av_frame_get_side_data(frame, AV_FRAME_DATA_MOTION_VECTORS)) {
        const auto* mv = reinterpret_cast<const AVMotionVector*>(sd->data);
        const std::size_t n = sd->size / sizeof(AVMotionVector);
        r.motion.reserve(n);
        for (std::size_t i = 0; i < n; ++i) {
          r.motion.push_back({mv[i].w, mv[i].h, mv[i].dst_x, mv[i].dst_y, mv[i].motion_y,
                              mv[i].motion_scale > 0 ? static_cast<int>(mv[i].motion_scale) : 1});
        }
      }
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
  // Each picture's motion vectors as side data: where its damage came from (picture_damage.hpp).
  c->export_side_data |= AV_CODEC_EXPORT_DATA_MVS;
  if (avcodec_open2(c, codec, nullptr) < 0) throw std::runtime_error("cannot open the H.264 decoder");
  std::lock_guard lock(reports_mutex);
  report_registry()[c] = &impl_->reports;
}

H264Decoder::~H264Decoder() = default;

DecodeResult H264Decoder::decode(std::string_view au) {
  DecodeResult r;
  if (au.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() - AV_INPUT_BUFFER_PADDING_SIZE)) {
    r.error = true;
    return r;
  }
  std::vector<uint8_t>& buf = impl_->padded;
  buf.resize(au.size() + AV_INPUT_BUFFER_PADDING_SIZE);  // reallocates only for a larger frame
  std::memcpy(buf.data(), au.data(), au.size());
  std::memset(buf.data() + au.size(), 0, AV_INPUT_BUFFER_PADDING_SIZE);
  const uint8_t* data = buf.data();
  int size = static_cast<int>(au.size());
  impl_->reports = DecodeReports{};
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
  const int mb_columns = (impl_->ctx->width + 15) / 16;
  for (const auto& [x, y] : impl_->reports.error_xy) r.error_mbs.push_back(y * mb_columns + x);
  r.concealed_mbs = impl_->reports.concealed_mbs;
  return r;
}

bool H264Decoder::latest_size(int& width_px, int& height_px) const {
  if (!impl_->have_latest) return false;
  width_px = impl_->latest->width;
  height_px = impl_->latest->height;
  return true;
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

// ---- Picture comparison ----

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
