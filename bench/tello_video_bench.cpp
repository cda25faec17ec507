// Video receiver latency on loopback: from the arrival of a frame's last datagram (stamped by
// the receiver thread) to the moment the decoded BGR frame is in the mailbox. The benchmark's
// time per iteration IS that latency (manual time). Arguments: slices per picture (1, or 45 as
// tello-sim sends) and datagram loss in percent (0, or 5: damaged frames are concealed and
// handed over; a frame whose last datagram is lost ends when the next frame's first arrives).
// A second benchmark times the decoder and the conversion alone on the same frames.
// BM_EncodeRendered / BM_DecodeRendered time the two ends of the co-simulation's sdk link on
// what it really carries: rendered 960 x 720 frames of the paper's shelf along an approach,
// with the default sensor noise, encoded as the simulated Tello encodes them.
// BM_EncodeRenderedNvenc and BM_NvencFidelity ask whether NVIDIA's hardware encoder could stand
// in for libx264 there: its wall time per frame, and what its pictures change for the flight
// software (both skip, with the reason, where NVENC cannot be opened).
//
//   build/release/bench/shelfcross_bench --benchmark_filter='Receiver|DecodeAndConvert|Rendered'
//   build/release/bench/shelfcross_bench --benchmark_filter='Nvenc|EncodeRendered'
#include <poll.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/perception/shelf_view.hpp"
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

// The simulated Tello's encoder settings (tello_emulator.cpp's: kTelloQp, `slices`, the
// encoder's own key interval a backstop at 4 x 30, every 30th capture forced to a key frame).
std::unique_ptr<verification::H264Encoder> tello_encoder(int slices, verification::H264Encoder::Backend backend) {
  return std::make_unique<verification::H264Encoder>(kWidth, kHeight, 30, 4 * 30, verification::H264Encoder::kTelloQp,
                                                     slices, backend);
}
bool forced_key(size_t frame_index) { return frame_index % 30 == 0; }

// The rendered approach through `encoder`, round and round: time per frame, bytes per frame.
void encode_rendered(benchmark::State& state, verification::H264Encoder& encoder) {
  const std::vector<cv::Mat>& frames = rendered_approach();
  size_t k = 0, bytes = 0, key_bytes = 0, keys = 0;
  for (auto _ : state) {
    const bool key = forced_key(k);
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

// libx264 as the simulated Tello runs it on the rendered approach; CPU time per frame.
void BM_EncodeRendered(benchmark::State& state) {
  const auto encoder = tello_encoder(static_cast<int>(state.range(0)), verification::H264Encoder::Backend::Libx264);
  encode_rendered(state, *encoder);
}
BENCHMARK(BM_EncodeRendered)->ArgName("slices")->Arg(1)->Arg(45)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond)
    ->Iterations(360);

// The NVENC encoder, or the reason it cannot be opened (the benchmark is then skipped).
std::unique_ptr<verification::H264Encoder> nvenc_or_skip(benchmark::State& state, int slices) {
  try {
    return tello_encoder(slices, verification::H264Encoder::Backend::Nvenc);
  } catch (const std::runtime_error& e) {
    state.SkipWithError(("no NVENC: " + std::string(e.what())).c_str());
    return nullptr;
  }
}

// The same with NVENC: the time reported is wall time per frame (the encoder works on the GPU,
// the CPU waits), the CPU column the process's CPU time per frame (colour conversion, upload,
// driver).
void BM_EncodeRenderedNvenc(benchmark::State& state) {
  const auto encoder = nvenc_or_skip(state, static_cast<int>(state.range(0)));
  if (encoder) encode_rendered(state, *encoder);
}
BENCHMARK(BM_EncodeRenderedNvenc)->ArgName("slices")->Arg(1)->Arg(45)->MeasureProcessCPUTime()->UseRealTime()
    ->Unit(benchmark::kMillisecond)->Iterations(360);

// tello_pilot's decoder and its conversion to BGR on the same stream (45 slices).
void BM_DecodeRendered(benchmark::State& state) {
  static const std::vector<std::string> stream = [] {
    const auto encoder = tello_encoder(45, verification::H264Encoder::Backend::Libx264);
    std::vector<std::string> out;
    size_t k = 0;
    for (const cv::Mat& f : rendered_approach()) out.push_back(encoder->encode(f, forced_key(k++)));
    return out;
  }();
  decode_and_convert(state, stream);
}
BENCHMARK(BM_DecodeRendered)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond)->Iterations(360);

// What the flight software sees in one picture: its tag blobs (TagDetector, default
// PerceptionParams, whole frame) and ArUco markers (MarkerDetector's reference pipeline, the
// shelf's default dictionary), markers by id (the first of an id seen twice).
struct Seen {
  std::vector<flight_sw::TagBlob> blobs;
  std::map<int, std::array<cv::Point2f, 4>> marker_corners_px;
};

struct FlightSoftwareEyes {
  flight_sw::TagDetector tags{flight_sw::PerceptionParams{}};
  flight_sw::MarkerDetector markers{flight_sw::KnownShelf{}.aruco_dictionary};
  std::vector<flight_sw::MarkerSighting> sightings;

  Seen look(const cv::Mat& bgr) {
    Seen seen;
    tags.detect(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows), seen.blobs);
    sightings.clear();  // detect appends
    markers.detect(bgr, sightings);
    for (const auto& m : sightings) seen.marker_corners_px.emplace(m.id, m.corners_px);
    return seen;
  }
};

// One backend's stream of the rendered approach, decoded by tello_pilot's decoder.
struct DecodedStream {
  std::vector<cv::Mat> pictures;
  size_t bytes = 0;
  int decode_errors = 0;     ///< access units that gave no picture or reported damage
  int keys_without_sps = 0;  ///< forced key frames without in-band SPS
};

DecodedStream encode_and_decode(verification::H264Encoder& encoder, const std::vector<cv::Mat>& frames) {
  H264Decoder decoder;
  DecodedStream out;
  for (size_t k = 0; k < frames.size(); ++k) {
    const std::string au = encoder.encode(frames[k], forced_key(k));
    out.bytes += au.size();
    const std::vector<int> types = sdk::nal_unit_types(au);
    if (forced_key(k) && std::find(types.begin(), types.end(), 7) == types.end()) ++out.keys_without_sps;
    const DecodeResult r = decoder.decode(au);
    if (r.error || r.pictures != 1) ++out.decode_errors;
    cv::Mat bgr;
    if (!decoder.latest_bgr(bgr)) bgr = cv::Mat::zeros(frames[k].size(), CV_8UC3);  // counted above
    out.pictures.push_back(bgr);
  }
  return out;
}

// Index of the blob of `blobs` nearest to `p_px` (-1 if none) and its distance (px).
std::pair<int, double> nearest_blob(const std::vector<flight_sw::TagBlob>& blobs, cv::Point2d p_px) {
  std::pair<int, double> best{-1, std::numeric_limits<double>::infinity()};
  for (size_t i = 0; i < blobs.size(); ++i) {
    const double d_px = cv::norm(blobs[i].centre_px - p_px);
    if (d_px < best.second) best = {static_cast<int>(i), d_px};
  }
  return best;
}

// How far `b` is from `a`, frame by frame, in what the flight software sees. Blobs are matched
// as mutual nearest neighbours (each the other's nearest centroid), so a blob seen on one side
// only is counted unmatched rather than measured against an unrelated blob; markers by id.
struct Agreement {
  double blob_max_px = 0.0;    ///< largest centroid distance of a matched pair
  double corner_max_px = 0.0;  ///< largest corner distance between markers of one id
  int blobs_unmatched = 0;     ///< blobs of either side in no pair
  int blob_count_frames = 0;   ///< frames where the blob counts differ
  int id_frames = 0;           ///< frames where the sets of marker ids differ
};

Agreement compare(const std::vector<Seen>& a, const std::vector<Seen>& b) {
  Agreement g;
  for (size_t k = 0; k < a.size(); ++k) {
    const auto& blobs_a = a[k].blobs;
    const auto& blobs_b = b[k].blobs;
    if (blobs_a.size() != blobs_b.size()) ++g.blob_count_frames;
    int pairs = 0;
    for (size_t j = 0; j < blobs_b.size(); ++j) {
      const auto [i, d_px] = nearest_blob(blobs_a, blobs_b[j].centre_px);
      if (i < 0 || nearest_blob(blobs_b, blobs_a[static_cast<size_t>(i)].centre_px).first != static_cast<int>(j)) continue;
      ++pairs;
      g.blob_max_px = std::max(g.blob_max_px, d_px);
    }
    g.blobs_unmatched += static_cast<int>(blobs_a.size() + blobs_b.size()) - 2 * pairs;
    bool same_ids = a[k].marker_corners_px.size() == b[k].marker_corners_px.size();
    for (const auto& [id, corners] : b[k].marker_corners_px) {
      const auto it = a[k].marker_corners_px.find(id);
      if (it == a[k].marker_corners_px.end()) {
        same_ids = false;
        continue;
      }
      for (size_t c = 0; c < 4; ++c) {
        g.corner_max_px = std::max(g.corner_max_px, static_cast<double>(cv::norm(corners[c] - it->second[c])));
      }
    }
    if (!same_ids) ++g.id_frames;
  }
  return g;
}

void report(benchmark::State& state, const std::string& pair, const Agreement& g) {
  state.counters[pair + "_blob_max_px"] = g.blob_max_px;
  state.counters[pair + "_blobs_unmatched"] = g.blobs_unmatched;
  state.counters[pair + "_blob_count_frames"] = g.blob_count_frames;
  state.counters[pair + "_corner_max_px"] = g.corner_max_px;
  state.counters[pair + "_id_frames"] = g.id_frames;
}

// How much the flight software saw over the frames: blobs, and marker ids.
void report(benchmark::State& state, const std::string& name, const std::vector<Seen>& seen) {
  size_t blobs = 0, markers = 0;
  for (const Seen& f : seen) blobs += f.blobs.size(), markers += f.marker_corners_px.size();
  state.counters[name + "_blobs"] = static_cast<double>(blobs);
  state.counters[name + "_marker_ids"] = static_cast<double>(markers);
}

// One backend's decodes against the source pictures (PSNR, dB) and what its stream cost.
void report(benchmark::State& state, const std::string& name, const DecodedStream& s, const std::vector<cv::Mat>& source) {
  double sum_db = 0.0, min_db = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < source.size(); ++k) {
    const double db = psnr_db(source[k], s.pictures[k]);
    sum_db += db;
    min_db = std::min(min_db, db);
  }
  state.counters[name + "_psnr_mean_db"] = sum_db / static_cast<double>(source.size());
  state.counters[name + "_psnr_min_db"] = min_db;
  state.counters[name + "_Mbit_per_s"] = 30.0 * 8e-6 * static_cast<double>(s.bytes) / static_cast<double>(source.size());
  state.counters[name + "_decode_errors"] = s.decode_errors;
  state.counters[name + "_keys_without_sps"] = s.keys_without_sps;
}

// The rendered approach (45 slices, a key frame every 30, as the emulator encodes it) through
// both backends and tello_pilot's decoder: each decode against the source picture, the two
// decodes against each other (mean and max absolute difference over all pixels and channels),
// and what the flight software sees on each: x264_vs_source is the codec's own effect,
// nvenc_vs_x264 what changing the backend would change. One iteration (the work is the
// comparison, not its time).
void BM_NvencFidelity(benchmark::State& state) {
  const auto nvenc = nvenc_or_skip(state, 45);
  if (!nvenc) return;
  const std::vector<cv::Mat>& source = rendered_approach();
  for (auto _ : state) {
    const DecodedStream x264 = encode_and_decode(*tello_encoder(45, verification::H264Encoder::Backend::Libx264), source);
    const DecodedStream hw = encode_and_decode(*nvenc, source);
    FlightSoftwareEyes eyes;
    std::vector<Seen> seen_source, seen_x264, seen_nvenc;
    double diff_sum = 0.0, diff_max = 0.0, diff_count = 0.0;
    for (size_t k = 0; k < source.size(); ++k) {
      seen_source.push_back(eyes.look(source[k]));
      seen_x264.push_back(eyes.look(x264.pictures[k]));
      seen_nvenc.push_back(eyes.look(hw.pictures[k]));
      cv::Mat diff;
      cv::absdiff(x264.pictures[k], hw.pictures[k], diff);
      const cv::Scalar channel_sums = cv::sum(diff);
      diff_sum += channel_sums[0] + channel_sums[1] + channel_sums[2];
      diff_count += static_cast<double>(diff.total() * 3);
      double k_max = 0.0;
      cv::minMaxLoc(diff.reshape(1), nullptr, &k_max);
      diff_max = std::max(diff_max, k_max);
    }
    report(state, "x264", x264, source);
    report(state, "nvenc", hw, source);
    report(state, "source", seen_source);
    report(state, "x264", seen_x264);
    report(state, "nvenc", seen_nvenc);
    state.counters["nvenc_vs_x264_absdiff_mean"] = diff_sum / diff_count;
    state.counters["nvenc_vs_x264_absdiff_max"] = diff_max;
    report(state, "x264_vs_source", compare(seen_source, seen_x264));
    report(state, "nvenc_vs_source", compare(seen_source, seen_nvenc));
    report(state, "nvenc_vs_x264", compare(seen_x264, seen_nvenc));
  }
}
BENCHMARK(BM_NvencFidelity)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace shelfcross::tello
