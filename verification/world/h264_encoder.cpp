#include "verification/world/h264_encoder.hpp"

#include <cstdint>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
#include <libavutil/opt.h>
}

#include "flight_sw/tello/h264_decoder.hpp"

namespace shelfcross::verification {

struct H264Encoder::Impl {
  AVCodecContext* ctx = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  /// The picture as planar YUV 4:2:0 (OpenCV's I420: Y rows, then U, then V), the frame's
  /// one buffer: cvtColor writes straight into what libx264 reads.
  cv::Mat i420;
  int64_t pts = 0;

  ~Impl() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&ctx);
  }
};

namespace {
// The frame's buffer is Impl::i420's memory, owned by the Mat: FFmpeg's reference must not
// free it.
void keep_buffer(void*, std::uint8_t*) {}

// libavcodec's text for an error code (av_err2str, which is C only).
std::string av_error_text(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

// One of the encoder's private options; a name this libavcodec does not know, or a value it
// refuses, is an error rather than a silently different stream.
void set_option(AVCodecContext* c, const char* name, const std::string& value) {
  const int err = av_opt_set(c->priv_data, name, value.c_str(), 0);
  if (err < 0) {
    throw std::runtime_error(std::string("H264Encoder: ") + c->codec->name + " option " + name + "=" + value + ": " +
                             av_error_text(err));
  }
}

void configure_libx264(AVCodecContext* c, int qp, int slices) {
  c->thread_count = 1;
  set_option(c, "preset", "ultrafast");
  set_option(c, "tune", "zerolatency");
  // Constant quantiser, the same for key and other frames (ipratio 1): a hardware encoder's
  // fixed-cost mode, and cheaper than CRF, which makes x264 compute a quarter-size copy of
  // every picture for its rate control (13 % of the encoding time on rendered frames).
  // Annex-B start codes, SPS/PPS before every key frame, no scene-cut key frames.
  set_option(c, "x264-params", "qp=" + std::to_string(qp) + ":ipratio=1.0:repeat-headers=1:annexb=1:scenecut=0:slices=" +
                                   std::to_string(slices));
}

// FFmpeg 5.1's h264_nvenc options (libavcodec/nvenc_h264.c). Constant QP: with init_qpP set,
// and init_qpI and init_qpB too, NVENC takes the three as given; `qp` alone would scale the
// key frames' by |i_quant_factor| (0.8 by default). Slices: sliceMode 3 (slices per picture)
// with AVCodecContext::slices. SPS/PPS: NVENC repeats them before every IDR unless the context
// asks for a global header, which it does not. The encoder reads system-memory YUV 4:2:0.
void configure_nvenc(AVCodecContext* c, int qp, int slices) {
  c->slices = slices;
  set_option(c, "preset", "p1");
  set_option(c, "tune", "ull");
  set_option(c, "zerolatency", "1");
  set_option(c, "delay", "0");
  set_option(c, "forced-idr", "1");
  set_option(c, "rc", "constqp");
  for (const char* name : {"init_qpI", "init_qpP", "init_qpB"}) set_option(c, name, std::to_string(qp));
}
}  // namespace

H264Encoder::H264Encoder(int width_px, int height_px, int fps, int key_interval, int qp, int slices, Backend backend)
    : impl_(std::make_unique<Impl>()) {
  tello::quiet_ffmpeg();
  if (width_px < 2 || height_px < 2 || width_px % 2 || height_px % 2) {
    throw std::invalid_argument("H264Encoder: 4:2:0 needs an even width and height, got " + std::to_string(width_px) +
                                " x " + std::to_string(height_px));
  }
  if (qp < 0 || qp > 51) throw std::invalid_argument("H264Encoder: qp must be 0..51, got " + std::to_string(qp));
  if (slices < 1 || slices > (height_px + 15) / 16) {
    throw std::invalid_argument("H264Encoder: slices must be 1.." + std::to_string((height_px + 15) / 16) +
                                " (macroblock rows), got " + std::to_string(slices));
  }
  const bool nvenc = backend == Backend::Nvenc;
  const AVCodec* codec = avcodec_find_encoder_by_name(nvenc ? "h264_nvenc" : "libx264");
  if (!codec) {
    throw std::runtime_error(nvenc ? "H264Encoder: this libavcodec has no NVENC encoder (h264_nvenc)"
                                   : "libavcodec has no libx264 encoder");
  }
  AVCodecContext* c = impl_->ctx = avcodec_alloc_context3(codec);
  if (!c) throw std::runtime_error("H.264 encoder: out of memory");
  c->width = width_px;
  c->height = height_px;
  c->time_base = AVRational{1, fps};
  c->framerate = AVRational{fps, 1};
  c->pix_fmt = AV_PIX_FMT_YUV420P;
  c->gop_size = key_interval;
  c->max_b_frames = 0;
  if (nvenc) {
    configure_nvenc(c, qp, slices);
  } else {
    configure_libx264(c, qp, slices);
  }
  if (const int err = avcodec_open2(c, codec, nullptr); err < 0) {
    if (nvenc) {
      throw std::runtime_error("H264Encoder: cannot open NVENC (h264_nvenc needs an NVIDIA GPU and its driver's "
                               "libcuda.so.1 and libnvidia-encode.so.1): " + av_error_text(err));
    }
    throw std::runtime_error("cannot open libx264: " + av_error_text(err));
  }
  impl_->frame = av_frame_alloc();
  impl_->packet = av_packet_alloc();
  if (!impl_->frame || !impl_->packet) throw std::runtime_error("H.264 encoder: out of memory");
  AVFrame* f = impl_->frame;
  f->format = AV_PIX_FMT_YUV420P;
  f->width = width_px;
  f->height = height_px;
  // One contiguous I420 picture, with FFmpeg's input padding after it (SIMD readers may read
  // up to AV_INPUT_BUFFER_PADDING_SIZE bytes past the last plane).
  const int w = width_px, h = height_px;
  const std::size_t picture_bytes = static_cast<std::size_t>(w) * h * 3 / 2;
  impl_->i420.create(1, static_cast<int>(picture_bytes + AV_INPUT_BUFFER_PADDING_SIZE), CV_8UC1);
  impl_->i420.setTo(0);
  std::uint8_t* y = impl_->i420.data;
  f->buf[0] = av_buffer_create(y, picture_bytes, keep_buffer, nullptr, 0);
  if (!f->buf[0]) throw std::runtime_error("H.264 encoder: out of memory");
  f->data[0] = y;
  f->data[1] = y + static_cast<std::size_t>(w) * h;
  f->data[2] = f->data[1] + static_cast<std::size_t>(w / 2) * (h / 2);
  f->linesize[0] = w;
  f->linesize[1] = f->linesize[2] = w / 2;
}

H264Encoder::~H264Encoder() = default;

std::string H264Encoder::encode(const cv::Mat& bgr, bool force_key_frame) {
  Impl& m = *impl_;
  if (bgr.type() != CV_8UC3 || bgr.cols != m.ctx->width || bgr.rows != m.ctx->height) {
    throw std::invalid_argument("H264Encoder::encode: expected a BGR image of the encoder's size");
  }
  // Both encoders copy each picture within the call that encodes it (libx264 into its frame
  // pool, NVENC into its input surface; no look-ahead, no B-frames, no output delay), so once
  // the last picture's packet is out FFmpeg holds no reference to the buffer and it may be
  // written again. (NVENC keeps the frame, and so the reference, when it has no free input
  // surface: this check catches that instead of overwriting a picture not yet encoded.)
  if (av_buffer_get_ref_count(m.frame->buf[0]) != 1) throw std::logic_error("H264Encoder: the picture is still referenced");
  // BGR -> YUV 4:2:0 (ITU-R BT.601, studio range, as libswscale's default) with OpenCV's
  // vectorised conversion, straight into the frame's buffer: libswscale has no unscaled fast
  // path from BGR24, and its generic scaler cost about a third as much as the encoding itself.
  const int w = bgr.cols, h = bgr.rows;
  cv::Mat picture(h * 3 / 2, w, CV_8UC1, m.i420.data);
  cv::cvtColor(bgr, picture, cv::COLOR_BGR2YUV_I420);
  CV_Assert(picture.data == m.i420.data);  // written in place, not reallocated
  m.frame->pts = m.pts++;
  m.frame->pict_type = force_key_frame ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  m.frame->key_frame = force_key_frame ? 1 : 0;
  if (const int err = avcodec_send_frame(m.ctx, m.frame); err < 0) {
    throw std::runtime_error(std::string("H264Encoder: ") + m.ctx->codec->name + " refused a frame: " + av_error_text(err));
  }
  std::string out;
  while (avcodec_receive_packet(m.ctx, m.packet) == 0) {
    out.append(reinterpret_cast<const char*>(m.packet->data), static_cast<size_t>(m.packet->size));
    av_packet_unref(m.packet);
  }
  // One access unit per frame is the stream's contract (the receiver and the emulator's
  // timing rely on it). Neither configuration holds a frame back; an encoder that did would
  // shift every later picture by a frame, so it is an error, not an empty access unit.
  if (out.empty()) {
    throw std::runtime_error(std::string("H264Encoder: ") + m.ctx->codec->name + " gave no access unit for a frame");
  }
  return out;
}

}  // namespace shelfcross::verification
