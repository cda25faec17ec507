// Video receiver latency on loopback: from the arrival of a frame's last datagram (stamped by
// the receiver thread) to the moment the decoded BGR frame is in the mailbox. The benchmark's
// time per iteration IS that latency (manual time). Arguments: slices per picture (1, or 45 as
// tello-sim sends) and datagram loss in percent (0, or 5: damaged frames are concealed and
// handed over; a frame whose last datagram is lost ends when the next frame's first arrives).
// A second benchmark times the decoder and the conversion alone on the same frames.
// BM_EncodeRendered / BM_DecodeRendered time the two ends of the co-simulation's sdk link on
// what it really carries: rendered 960 x 720 frames of the paper's shelf along an approach,
// with the default sensor noise, encoded as the simulated Tello encodes them.
//
//   build/release/bench/shelfcross_bench --benchmark_filter='Receiver|DecodeAndConvert|Rendered'
#include <poll.h>

#include <cmath>

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/h264_decoder.hpp"
#include "flight_sw/tello/video_receiver.hpp"
#include "render/renderer.hpp"
#include "render/test/test_warehouse.hpp"
#include "sdk/video_framing.hpp"
#include "shelfcross/random.hpp"
#include "verification/world/h264_encoder.hpp"  // the drone's side: a Tello-like stream

namespace shelfcross::tello {
namespace {

constexpr int kWidth = 960, kHeight = 720, kFrames = 60, kKeyInterval = 30;

// A Tello-like sequence: textured background, moving bright blocks; key frame every 30.
std::vector<std::string> encoded_frames(int slices = 1) {
  cv::Mat base(kHeight, kWidth, CV_8UC3);
  RandomStream rng(11, StreamId::render_noise);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const auto n = static_cast<uchar>(rng.below(32));
      base.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(60 + n), static_cast<uchar>(80 + y / 8 + n), static_cast<uchar>(100 + x / 10));
    }
  }
  verification::H264Encoder encoder(kWidth, kHeight, 30, kKeyInterval, verification::H264Encoder::kTelloQp, slices);
  std::vector<std::string> out;
  for (int k = 0; k < kFrames; ++k) {
    cv::Mat f = base.clone();
    f(cv::Rect(50 + 10 * k, 100, 200, 200)).setTo(cv::Scalar(250, 250, 250));
    f(cv::Rect(500, 200 + 5 * k, 150, 100)).setTo(cv::Scalar(30, 200, 40));
    out.push_back(encoder.encode(f));
  }
  return out;
}

void BM_ReceiverLastDatagramToHandOver(benchmark::State& state) {
  const int slices = static_cast<int>(state.range(0));
  const double loss = static_cast<double>(state.range(1)) / 100.0;
  const std::vector<std::string> frames = encoded_frames(slices);
  RandomStream drops(5, StreamId::link_faults);
  const SteadyClock clock;
  UdpSocket sender("127.0.0.1", 0);
  VideoReceiverConfig config;
  config.drone_ip = "127.0.0.1";
  config.local_ip = "127.0.0.1";
  config.local_port = 0;
  VideoReceiver receiver(config, clock);
  const Endpoint to{"127.0.0.1", receiver.local_port()};
  std::vector<std::vector<std::string>> datagrams;
  for (const auto& f : frames) datagrams.push_back(sdk::tello_datagrams(f));
  size_t k = 0;
  double total_s = 0.0, worst_s = 0.0;
  int64_t n = 0;
  int64_t missed = 0;
  // Until the receiver has its first clean key frame (with loss, several groups may pass).
  for (int warm = 0; warm < 100 * kKeyInterval && receiver.stats().handed == 0; ++warm) {
    for (const auto& d : datagrams[k % datagrams.size()]) {
      if (!drops.bernoulli(loss)) sender.send_to(to, d);
    }
    ++k;
    pollfd p{receiver.notify_fd(), POLLIN, 0};
    ::poll(&p, 1, 5);
  }
  receiver.take_latest();
  for (auto _ : state) {
    std::optional<VideoFrame> f;
    // Frames until one is handed over (with loss, a frame may give no picture or end late).
    for (int tries = 0; tries < 8 && !f; ++tries) {
      for (const auto& d : datagrams[k % datagrams.size()]) {
        if (!drops.bernoulli(loss)) sender.send_to(to, d);
      }
      ++k;
      for (int guard = 0; guard < (loss > 0.0 ? 4 : 2000) && !f; ++guard) {
        pollfd p{receiver.notify_fd(), POLLIN, 0};
        ::poll(&p, 1, 5);
        f = receiver.take_latest();
      }
      if (!f) ++missed;
    }
    if (!f) {
      state.SkipWithError(("no frame handed over: " + receiver.stats().text()).c_str());
      break;
    }
    const double latency_s = ns_to_seconds(f->handed_ns - f->t_ns);
    state.SetIterationTime(latency_s);
    total_s += latency_s;
    worst_s = std::max(worst_s, latency_s);
    ++n;
  }
  state.counters["mean_ms"] = n ? 1e3 * total_s / static_cast<double>(n) : 0.0;
  state.counters["max_ms"] = 1e3 * worst_s;
  state.counters["bytes_per_frame"] = static_cast<double>(receiver.stats().bytes) / static_cast<double>(std::max<int64_t>(1, n));
  state.counters["damaged_share"] =
      static_cast<double>(receiver.stats().handed_damaged) / static_cast<double>(std::max<int64_t>(1, receiver.stats().handed));
  state.counters["frames_without_hand_over"] = static_cast<double>(missed);
}
BENCHMARK(BM_ReceiverLastDatagramToHandOver)
    ->ArgNames({"slices", "loss_pct"})
    ->Args({1, 0})
    ->Args({45, 0})
    ->Args({45, 5})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(600);

// One access unit of `stream` decoded and converted to BGR per iteration, round and round.
void decode_and_convert(benchmark::State& state, const std::vector<std::string>& stream) {
  H264Decoder decoder;
  cv::Mat bgr;
  size_t k = 0;
  for (auto _ : state) {
    const DecodeResult r = decoder.decode(stream[k++ % stream.size()]);
    benchmark::DoNotOptimize(r);
    decoder.latest_bgr(bgr);
    benchmark::DoNotOptimize(bgr.data);
  }
}

void BM_DecodeAndConvert(benchmark::State& state) {
  static const std::vector<std::string> frames = encoded_frames();
  decode_and_convert(state, frames);
}
BENCHMARK(BM_DecodeAndConvert)->Unit(benchmark::kMillisecond)->Iterations(600);

// 90 frames (3 s at 30 fps) of the approach to the paper's shelf: from 2.4 m to 0.9 m in front
// of it at 0.5 m/s, swaying sideways by +-5 cm and turning by +-3 degrees as a hovering Tello
// does, with the scenarios' default sensor noise (2 grey levels), noise seed per frame.
const std::vector<cv::Mat>& rendered_approach() {
  static const std::vector<cv::Mat> frames = [] {
    cv::setNumThreads(1);
    render::RenderOptions options;
    options.noise_stddev = 2.0;
    render::Renderer renderer(render::test::paper_test_shelf(), CameraIntrinsics{}, options);
    std::vector<cv::Mat> out;
    for (int k = 0; k < 90; ++k) {
      const double t_s = k / 30.0;
      const Eigen::Vector3d p_WC_m(0.6 + 0.5 * t_s, 0.05 * std::sin(2.0 * t_s), 0.98);
      out.push_back(renderer.render(render::test::camera_looking_forward(p_WC_m, 0.05 * std::sin(3.0 * t_s)),
                                    static_cast<std::uint64_t>(k + 1)));
    }
    return out;
  }();
  return frames;
}

// The simulated Tello's encoder (tello_emulator.cpp's settings: 45 slices, kTelloQp, a key frame
// every 30 captures) on the rendered approach; CPU time per frame, bytes per frame.
void BM_EncodeRendered(benchmark::State& state) {
  const std::vector<cv::Mat>& frames = rendered_approach();
  verification::H264Encoder encoder(kWidth, kHeight, 30, 120, verification::H264Encoder::kTelloQp, static_cast<int>(state.range(0)));
  size_t k = 0, bytes = 0, key_bytes = 0, keys = 0;
  for (auto _ : state) {
    const bool key = k % 30 == 0;
    const std::string au = encoder.encode(frames[k % frames.size()], key);
    bytes += au.size();
    if (key) key_bytes += au.size(), ++keys;
    ++k;
  }
  state.counters["bytes_per_frame"] = static_cast<double>(bytes) / static_cast<double>(std::max<size_t>(1, k));
  state.counters["bytes_per_key_frame"] = static_cast<double>(key_bytes) / static_cast<double>(std::max<size_t>(1, keys));
  state.counters["bytes_per_other_frame"] =
      static_cast<double>(bytes - key_bytes) / static_cast<double>(std::max<size_t>(1, k - keys));
  state.counters["Mbit_per_s_at_30fps"] = 30.0 * 8e-6 * static_cast<double>(bytes) / static_cast<double>(std::max<size_t>(1, k));
}
BENCHMARK(BM_EncodeRendered)->ArgName("slices")->Arg(1)->Arg(45)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond)
    ->Iterations(360);

// tello_pilot's decoder and its conversion to BGR on the same stream (45 slices).
void BM_DecodeRendered(benchmark::State& state) {
  static const std::vector<std::string> stream = [] {
    verification::H264Encoder encoder(kWidth, kHeight, 30, 120, verification::H264Encoder::kTelloQp, 45);
    std::vector<std::string> out;
    size_t k = 0;
    for (const cv::Mat& f : rendered_approach()) out.push_back(encoder.encode(f, k++ % 30 == 0));
    return out;
  }();
  decode_and_convert(state, stream);
}
BENCHMARK(BM_DecodeRendered)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond)->Iterations(360);

}  // namespace
}  // namespace shelfcross::tello
