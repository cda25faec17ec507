// Perception latency: every stage of the flight software's perception and its whole
// per-frame step, on the benchmark frame set (bench/frame_set.hpp), single-threaded, next to
// the stock-OpenCV baseline in the same run. How to run and read it: bench/README.md.
//
//   build/release/bench/shelfcross_bench --benchmark_filter='Perception|Step|Baseline' \
//       --benchmark_format=json --benchmark_out=build/perception_bench.json
//
// Every benchmark times one call per iteration (manual time: the calling thread's CPU time,
// see thread_cpu_s), cycling over its frames, so Google Benchmark's real_time is the mean per
// call; the counters add mean_ms, p50_ms, p99_ms and max_ms over those calls (and min, p10, p25,
// p75, p90: the quantiles verification/scenario/cosim_settings.hpp takes), and frames (distinct frames
// used).
//
// Frames: SHELFCROSS_BENCH_FRAMES (default <source>/build/bench_frames), generated on first
// use from SHELFCROSS_BENCH_SCENARIO (default scenarios/paper_test_shelf.yaml) when missing or
// stale. SHELFCROSS_BENCH_IMAGES=<folder> benchmarks a folder of recorded images instead (with
// the flight configuration SHELFCROSS_BENCH_CONFIG, default flight_sw/config/paper_test_shelf.yaml).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <map>
#include <set>
#include <memory>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/tracking.hpp>
#include <opencv2/tracking/tracking_legacy.hpp>

#include "flight_sw/control/control.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/frames/frame_set.hpp"

namespace shelfcross::bench {
using namespace shelfcross::frames;  // the frame set this benchmark reads
namespace {

/// The calling thread's CPU time: on an idle core the same as wall time (everything runs on
/// this thread: OpenCV is set to one thread), and unaffected by other processes sharing the
/// machine, which would otherwise put their time slices into the tail percentiles.
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
using flight_sw::FlightConfig;
using flight_sw::PerceptionPipeline;
using flight_sw::TagBlob;

const char* env_or(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

bool recorded_mode() { return std::getenv("SHELFCROSS_BENCH_IMAGES") && *std::getenv("SHELFCROSS_BENCH_IMAGES"); }

/// Per-frame inputs of the later stages, prepared once (untimed) with the fast pipeline.
struct FrameInputs {
  cv::Rect roi;       ///< where the step looks for tags (whole frame, or the target's window)
  int stride = 0;     ///< tag seed stride there (0: the configured whole-frame one)
  std::vector<TagBlob> tags;        ///< detected in roi (before eq. 1)
  std::vector<TagBlob> front_tags;  ///< after eq. 1
  std::vector<cv::Point3d> pnp_object;  ///< tag centres on the shelf (G or K frame)
  std::vector<cv::Point2d> pnp_pixels;  ///< their blob centroids in the image
  cv::Rect grid_px;                     ///< the front tags' bounding box (marker region)
  double marker_side_px = 0.0;
  std::optional<cv::Rect2d> target_box;  ///< the target's tracked box after this frame's step
};

struct Data {
  FrameSet set;
  FlightConfig config;
  std::map<const Frame*, FrameInputs> inputs;
  std::string error;
};

/// Fills per-frame inputs: stills and sequences are analysed as the flight software does
/// (whole frame: tags, eq. 1, grid); approach frames get the window and tags of the fast
/// flight software's own step on them (a SequencePlayer over each sequence).
void prepare_inputs(Data& d) {
  FlightConfig fast = d.config;
  fast.perception.pipeline = PerceptionPipeline::fast;
  flight_sw::TagDetector detector(fast.perception);
  for (const Frame& f : d.set.frames) {
    FrameInputs& in = d.inputs[&f];
    in.roi = cv::Rect(0, 0, f.bgr.cols, f.bgr.rows);
    flight_sw::ShelfView view;
    flight_sw::analyse_shelf(f.bgr, detector, fast, view);
    detector.detect(f.bgr, in.roi, in.tags);
    in.front_tags = view.tags;
    if (!view.tags.empty()) {
      in.grid_px = view.tags.front().bbox_px;
      for (const TagBlob& t : view.tags) in.grid_px |= t.bbox_px;
      in.marker_side_px = fast.shelf.marker_size_m * view.px_per_m;
    }
    if (view.full) {  // the viewpoint's PnP: every tag of the grid
      for (int r = 0; r < view.grid.rows; ++r) {
        for (int c = 0; c < view.grid.columns; ++c) {
          in.pnp_object.push_back(flight_sw::grid_tag_G(fast.shelf, c, r));
          in.pnp_pixels.push_back(view.tags[static_cast<size_t>(view.grid.at(r, c))].centre_px);
        }
      }
    }
  }
  // Approach windows: the fast flight software's tracked box on each frame of each sequence.
  std::vector<std::string> conditions;
  for (const Frame& f : d.set.frames) {
    if (f.spec.step >= 0 && std::find(conditions.begin(), conditions.end(), f.spec.condition) == conditions.end()) {
      conditions.push_back(f.spec.condition);
    }
  }
  for (const std::string& c : conditions) {
    SequencePlayer player(fast, d.set.sequence(c));
    std::optional<cv::Rect2d> box_before;
    while (const Frame* f = player.next()) {
      const bool approaching = player.driver().fsw().phase() == flight_sw::Phase::Approach;
      player.driver().step_frame();
      const flight_sw::FlightSoftware& fsw = player.driver().fsw();
      FrameInputs& in = d.inputs[f];
      if (approaching && box_before) {
        const cv::Rect2d& b = *box_before;
        const double gx = fast.perception.roi_expand * b.width, gy = fast.perception.roi_expand * b.height;
        in.roi = cv::Rect(cv::Point(static_cast<int>(b.x - gx), static_cast<int>(b.y - gy)),
                          cv::Point(static_cast<int>(b.br().x + gx), static_cast<int>(b.br().y + gy))) &
                 cv::Rect(0, 0, f->bgr.cols, f->bgr.rows);
        const double side = 0.5 * std::min(b.width, b.height) / 4.0;  // ~ a tag side: 1/8 of a cell box
        in.stride = std::clamp(static_cast<int>(0.4 * side), 2, 8);
        in.tags.clear();
        detector.detect(f->bgr, in.roi, in.tags, in.stride);
        in.front_tags = in.tags;
        flight_sw::keep_front_shelf(in.front_tags, fast.perception.area_ratio_threshold);
        // The four corner tags: the front tags nearest the tracked box's corners, shrunk by half a tag.
        const auto& t = fsw.telemetry();
        if (t.tracking.target && t.tracking.tracked_box_px) {
          const cv::Rect2d& q = *t.tracking.tracked_box_px;
          const double h = 0.5 * side;
          const std::array<cv::Point2d, 4> corners{cv::Point2d(q.x + h, q.br().y - h), cv::Point2d(q.br().x - h, q.br().y - h),
                                                   cv::Point2d(q.br().x - h, q.y + h), cv::Point2d(q.x + h, q.y + h)};
          const auto obj = flight_sw::cell_corner_tags_K(fast.shelf, *t.tracking.target);
          in.pnp_object.clear();
          in.pnp_pixels.clear();
          for (size_t k = 0; k < 4 && !in.front_tags.empty(); ++k) {
            const auto best = std::min_element(in.front_tags.begin(), in.front_tags.end(), [&](const TagBlob& a, const TagBlob& b2) {
              return cv::norm(a.centre_px - corners[k]) < cv::norm(b2.centre_px - corners[k]);
            });
            in.pnp_object.push_back(obj[k]);
            in.pnp_pixels.push_back(best->centre_px);
          }
        }
      }
      box_before = fsw.telemetry().tracking.tracked_box_px;
      in.target_box = fsw.telemetry().tracking.tracked_box_px;
    }
  }
}

Data& data() {
  static Data d = [] {
    cv::setNumThreads(1);
    ::setenv("LP_NUM_THREADS", "1", 0);
    Data d;
    try {
      if (recorded_mode()) {
        d.config = flight_sw::load_flight_config(
            env_or("SHELFCROSS_BENCH_CONFIG", SHELFCROSS_SOURCE_DIR "/flight_sw/config/paper_test_shelf.yaml"));
        d.set = load_image_folder(std::getenv("SHELFCROSS_BENCH_IMAGES"), d.config.camera.width_px, d.config.camera.height_px);
      } else {
        const verification::Scenario sc = verification::load_scenario(
            env_or("SHELFCROSS_BENCH_SCENARIO", SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml"));
        const std::filesystem::path dir = env_or("SHELFCROSS_BENCH_FRAMES", SHELFCROSS_SOURCE_DIR "/build/bench_frames");
        if (auto why = frame_set_stale(dir, sc)) {
          std::cerr << "perception bench: generating the frame set in " << dir.string() << " (" << *why << ")\n";
          generate_frame_set(sc, dir);
        }
        d.set = load_frame_set(dir, sc);
        d.config = verification::flight_config_for(sc, sc.camera);
      }
      prepare_inputs(d);
      std::cerr << "perception bench: " << d.set.frames.size() << " frames from " << d.set.source << "\n";
    } catch (const std::exception& e) {
      d.error = e.what();
    }
    return d;
  }();
  return d;
}

// ---- Timing and statistics ----

class Samples {
 public:
  explicit Samples(benchmark::State& state) : state_(state) { ms_.reserve(static_cast<size_t>(state.max_iterations)); }
  /// Times f() and records it as this iteration's time.
  template <class F>
  void time(F&& f) {
    const double t0 = thread_cpu_s();
    f();
    const double s = thread_cpu_s() - t0;
    state_.SetIterationTime(s);
    ms_.push_back(1e3 * s);
  }
  void finish(size_t distinct_frames) {
    if (ms_.empty()) return;
    std::vector<double> v = ms_;
    std::sort(v.begin(), v.end());
    const auto q = [&](double p) { return v[static_cast<size_t>(std::floor(p * static_cast<double>(v.size() - 1)))]; };
    double sum = 0.0;
    for (double x : v) sum += x;
    state_.counters["mean_ms"] = sum / static_cast<double>(v.size());
    state_.counters["min_ms"] = v.front();
    state_.counters["p10_ms"] = q(0.10);
    state_.counters["p25_ms"] = q(0.25);
    state_.counters["p50_ms"] = q(0.50);
    state_.counters["p75_ms"] = q(0.75);
    state_.counters["p90_ms"] = q(0.90);
    state_.counters["p99_ms"] = q(0.99);
    state_.counters["max_ms"] = v.back();
    state_.counters["frames"] = static_cast<double>(distinct_frames);
  }

 private:
  benchmark::State& state_;
  std::vector<double> ms_;
};

std::vector<const Frame*> frames_of(const std::string& group) {
  std::vector<const Frame*> v;
  for (const Frame& f : data().set.frames) {
    if (group == "all" || f.spec.group == group) v.push_back(&f);
  }
  return v;
}

/// Runs `body(frame, inputs, samples)` once per iteration over the group's frames, cycling.
void over_frames(benchmark::State& state, const std::string& group,
                 const std::function<void(const Frame&, const FrameInputs&, Samples&)>& body,
                 const std::function<bool(const FrameInputs&)>& usable = {}) {
  Data& d = data();
  if (!d.error.empty()) return state.SkipWithError(d.error.c_str());
  std::vector<const Frame*> frames;
  for (const Frame* f : frames_of(group)) {
    if (!usable || usable(d.inputs.at(f))) frames.push_back(f);
  }
  if (frames.empty()) return state.SkipWithError(("no usable frames in group " + group).c_str());
  Samples samples(state);
  size_t i = 0;
  for (auto _ : state) {
    const Frame* f = frames[i++ % frames.size()];
    body(*f, d.inputs.at(f), samples);
  }
  samples.finish(frames.size());
}

FlightConfig config_with(PerceptionPipeline p) {
  FlightConfig c = data().config;
  c.perception.pipeline = p;
  return c;
}

// ---- Stages (fast pipeline unless named Reference) ----

void BM_PerceptionTags(benchmark::State& state, std::string group, PerceptionPipeline pipeline) {
  flight_sw::TagDetector detector(config_with(pipeline).perception);
  std::vector<TagBlob> out;
  out.reserve(256);
  over_frames(state, group, [&](const Frame& f, const FrameInputs& in, Samples& s) {
    out.clear();
    s.time([&] { detector.detect(f.bgr, in.roi, out, in.stride); });
    benchmark::DoNotOptimize(out.data());
  });
}

void BM_PerceptionEq1(benchmark::State& state, std::string group) {
  const double threshold = data().config.perception.area_ratio_threshold;
  std::vector<TagBlob> work;
  work.reserve(256);
  over_frames(state, group, [&](const Frame&, const FrameInputs& in, Samples& s) {
    work.assign(in.tags.begin(), in.tags.end());
    s.time([&] { benchmark::DoNotOptimize(flight_sw::keep_front_shelf(work, threshold)); });
  }, [](const FrameInputs& in) { return !in.tags.empty(); });
}

void BM_PerceptionStairs(benchmark::State& state, std::string group) {
  const FlightConfig& c = data().config;
  std::vector<cv::Point2d> pts;
  over_frames(state, group, [&](const Frame&, const FrameInputs& in, Samples& s) {
    pts.clear();
    for (const TagBlob& t : in.front_tags) pts.push_back(t.centre_px);
    s.time([&] {
      const double px_per_m = flight_sw::tag_scale_px_per_m(in.front_tags, c.shelf);
      const auto grid = flight_sw::classify_grid(pts, flight_sw::grid_limits(c.shelf, px_per_m),
                                                 c.perception.grid_orthogonality_tolerance_rad);
      benchmark::DoNotOptimize(grid.valid);
    });
  }, [](const FrameInputs& in) { return in.front_tags.size() >= 2; });
}

void BM_PerceptionAruco(benchmark::State& state, std::string group, PerceptionPipeline pipeline) {
  flight_sw::MarkerDetector detector(data().config.shelf.aruco_dictionary);
  std::vector<flight_sw::MarkerSighting> out;
  over_frames(state, group, [&](const Frame& f, const FrameInputs& in, Samples& s) {
    out.clear();
    if (pipeline == PerceptionPipeline::fast) {
      s.time([&] { detector.detect_in(f.bgr, in.grid_px, in.marker_side_px, data().config.perception.marker_area_ratio_threshold, out); });
    } else {
      s.time([&] { detector.detect(f.bgr, out); });
    }
  }, [](const FrameInputs& in) { return in.marker_side_px > 0.0; });
}

void BM_PerceptionPnP(benchmark::State& state, std::string group) {
  const FlightConfig& c = data().config;
  over_frames(state, group, [&](const Frame&, const FrameInputs& in, Samples& s) {
    s.time([&] { benchmark::DoNotOptimize(flight_sw::estimate_pose(in.pnp_object, in.pnp_pixels, c.camera, c.mount)); });
  }, [](const FrameInputs& in) { return in.pnp_pixels.size() >= 4; });
}

/// Tracking over the approach frames in sequence order (the tracker needs consecutive frames):
/// fast = BoxTracker prediction and correction; reference = Median Flow update.
void BM_PerceptionTracking(benchmark::State& state, PerceptionPipeline pipeline) {
  Data& d = data();
  if (!d.error.empty()) return state.SkipWithError(d.error.c_str());
  std::vector<const Frame*> frames;
  for (const Frame& f : d.set.frames) {
    if (f.spec.step >= 0 && d.inputs.at(&f).target_box && (f.spec.group == "approach" || f.spec.group == "close" || f.spec.group == "recorded")) {
      frames.push_back(&f);
    }
  }
  if (frames.size() < 2) return state.SkipWithError("no approach frames with a tracked box");
  Samples samples(state);
  size_t i = 0;
  flight_sw::BoxTracker box_tracker;
  cv::Ptr<cv::legacy::Tracker> median_flow;
  TimeNs t = 0;
  for (auto _ : state) {
    const size_t k = i++ % frames.size();
    const Frame& f = *frames[k];
    const cv::Rect2d& truth = *d.inputs.at(&f).target_box;
    t += 33'333'333;
    const bool restart = k == 0 || frames[k - 1]->spec.condition != f.spec.condition;
    if (restart) {  // untimed: a new sequence
      box_tracker.init(truth, t);
      if (pipeline == PerceptionPipeline::reference) {
        median_flow = cv::legacy::TrackerMedianFlow::create();
        median_flow->init(f.bgr, truth);
      }
      state.SetIterationTime(0.0);
      continue;
    }
    if (pipeline == PerceptionPipeline::fast) {
      samples.time([&] {
        benchmark::DoNotOptimize(box_tracker.predict(t));
        box_tracker.correct(truth, t);
      });
    } else {
      cv::Rect2d box;
      samples.time([&] { benchmark::DoNotOptimize(median_flow->update(f.bgr, box)); });
    }
  }
  samples.finish(frames.size());
}

void BM_PerceptionControl(benchmark::State& state) {
  const FlightConfig& c = data().config;
  flight_sw::PiController pi_z({c.control.kp_z, c.control.ki_z, c.control.z_integral_limit_m_s, c.control.z_speed_max_mps});
  flight_sw::PiController pi_psi({c.control.kp_psi, c.control.ki_psi, c.control.psi_integral_limit_rad_s, c.control.yaw_rate_max_radps});
  Samples samples(state);
  int k = 0;
  for (auto _ : state) {
    const double e = 0.05 * std::sin(0.1 * k++);
    samples.time([&] {
      flight_sw::VelocityCommand v;
      v.vz_mps = pi_z.update(e, 1.0 / 30.0);                                   // eq. 12
      v.yaw_rate_radps = pi_psi.update(0.5 * e, 1.0 / 30.0);                   // eq. 15
      v.vy_B_mps = flight_sw::bang_off_bang(e, c.control.psi_lateral_threshold_rad, c.control.lateral_speed_mps);
      v.vx_B_mps = c.control.forward_speed_mps;                                // eq. 10
      benchmark::DoNotOptimize(flight_sw::to_rc(v, c.rc).text());
    });
  }
  samples.finish(0);
}

// ---- The whole flight-software step ----

flight_sw::Phase phase_of(const std::string& phase) {
  using flight_sw::Phase;
  if (phase == "search") return Phase::FindShelf;
  if (phase == "viewpoint") return Phase::GoToViewpoint;
  if (phase == "inventory") return Phase::TakeInventory;
  return Phase::Approach;
}

/// One iteration = one FlightSoftware::step on a frame handled in `phase`; the frames and
/// messages before it (and after the sequence's end, a fresh flight software) go untimed.
void BM_Step(benchmark::State& state, std::string condition, std::string phase, PerceptionPipeline pipeline) {
  Data& d = data();
  if (!d.error.empty()) return state.SkipWithError(d.error.c_str());
  const std::vector<const Frame*> seq = d.set.sequence(condition);
  if (seq.empty()) return state.SkipWithError(("no sequence " + condition).c_str());
  SequencePlayer player(config_with(pipeline), seq);
  const flight_sw::Phase wanted = phase_of(phase);
  Samples samples(state);
  std::set<const Frame*> used;
  for (auto _ : state) {
    bool timed = false;
    for (int guard = 0; !timed; ++guard) {
      const Frame* f = player.next();
      if (!f) {
        if (used.empty() && guard > 2 * static_cast<int>(seq.size()) + SequencePlayer::kMaxViewpointSteps) {
          state.SkipWithError(("no frame of " + condition + " is handled in phase " + phase).c_str());
          return;
        }
        player.restart();
        continue;
      }
      const flight_sw::Phase now = player.driver().fsw().phase();
      if (now > wanted) {  // past it: the rest of the sequence would be untimed anyway
        player.restart();
        continue;
      }
      if (now == wanted) {
        samples.time([&] { player.driver().step_frame(); });
        used.insert(f);
        timed = true;
      } else {
        player.driver().step_frame();
      }
    }
  }
  samples.finish(used.size());
}

// ---- The stock-OpenCV baseline ----

/// The straightforward composition of stock OpenCV calls on the whole frame, as a first
/// implementation would be written: HSV conversion, inRange, external contours with area,
/// fill and aspect filters and eq. 1; ArUco with default parameters; default Median Flow;
/// iterative solvePnP on the four corner tags. Frames in sequence order so that Median Flow
/// tracks; restarted (untimed) at each sequence.
void BM_Baseline(benchmark::State& state, std::string group) {
  Data& d = data();
  if (!d.error.empty()) return state.SkipWithError(d.error.c_str());
  const FlightConfig& c = d.config;
  std::vector<const Frame*> frames = frames_of(group);
  if (frames.empty()) return state.SkipWithError(("no frames in group " + group).c_str());
  const auto dict = cv::aruco::getPredefinedDictionary(*flight_sw::aruco_dictionary_id(c.shelf.aruco_dictionary));
  const auto params = cv::aruco::DetectorParameters::create();
  const cv::Matx33d K(c.camera.fx_px, 0, c.camera.cx_px, 0, c.camera.fy_px, c.camera.cy_px, 0, 0, 1);
  const cv::Vec<double, 5> dist(c.camera.k1, c.camera.k2, c.camera.p1, c.camera.p2, c.camera.k3);
  const flight_sw::HsvRange& r = c.perception.tag_hsv;
  cv::Ptr<cv::legacy::Tracker> tracker;
  Samples samples(state);
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % frames.size();
    const Frame& f = *frames[k];
    const FrameInputs& in = d.inputs.at(&f);
    const cv::Rect2d box0 = in.target_box.value_or(cv::Rect2d(380, 260, 200, 200));
    if (k == 0 || frames[k - 1]->spec.condition != f.spec.condition || frames[k - 1]->spec.step + 1 != f.spec.step) {
      tracker = cv::legacy::TrackerMedianFlow::create();  // untimed
      tracker->init(f.bgr, box0);
    }
    std::vector<cv::Point3d> obj = in.pnp_object;
    std::vector<cv::Point2d> px = in.pnp_pixels;
    if (obj.size() < 4) {  // no target in this frame: the grid's first four tags stand in
      obj = {{-0.01, 0.1, 0.1}, {-0.01, -0.1, 0.1}, {-0.01, -0.1, -0.1}, {-0.01, 0.1, -0.1}};
      px = {{400, 300}, {520, 300}, {520, 420}, {400, 420}};
    }
    samples.time([&] {
      cv::Mat hsv, mask, gray;
      cv::cvtColor(f.bgr, hsv, cv::COLOR_BGR2HSV);
      cv::inRange(hsv, cv::Scalar(std::min(r.hue_min, r.hue_max), r.sat_min, r.val_min),
                  cv::Scalar(std::max(r.hue_min, r.hue_max), r.sat_max, r.val_max), mask);
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
      std::vector<std::pair<double, cv::Point2d>> tags;
      double largest = 0.0;
      for (const auto& ct : contours) {
        const double area = cv::contourArea(ct);
        const cv::Rect bb = cv::boundingRect(ct);
        if (area < c.perception.min_tag_area_px || area < c.perception.min_fill_ratio * bb.area()) continue;
        const cv::Moments m = cv::moments(ct);
        tags.push_back({area, {m.m10 / m.m00, m.m01 / m.m00}});
        largest = std::max(largest, area);
      }
      std::erase_if(tags, [&](const auto& t) { return t.first < c.perception.area_ratio_threshold * largest; });
      cv::cvtColor(f.bgr, gray, cv::COLOR_BGR2GRAY);
      std::vector<std::vector<cv::Point2f>> corners;
      std::vector<int> ids;
      cv::aruco::detectMarkers(gray, dict, corners, ids, params);
      cv::Rect2d box;
      tracker->update(f.bgr, box);
      cv::Vec3d rvec, tvec;
      cv::solvePnP(obj, px, K, dist, rvec, tvec, false, cv::SOLVEPNP_ITERATIVE);
      benchmark::DoNotOptimize(tags.data());
      benchmark::DoNotOptimize(ids.data());
    });
  }
  samples.finish(frames.size());
}

// ---- Registration ----

template <class... A>
benchmark::internal::Benchmark* reg(const std::string& name, void (*fn)(benchmark::State&, A...), A... args) {
  return benchmark::RegisterBenchmark(name.c_str(), fn, args...)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
}

const bool kRegistered = [] {
  constexpr auto F = PerceptionPipeline::fast;
  constexpr auto R = PerceptionPipeline::reference;
  const bool recorded = recorded_mode();
  const std::vector<std::string> groups =
      recorded ? std::vector<std::string>{"recorded"} : std::vector<std::string>{"far", "viewpoint", "approach", "close"};
  for (const std::string& g : groups) {
    reg("BM_PerceptionTags/" + g, BM_PerceptionTags, g, F)->Iterations(600);
    reg("BM_PerceptionTagsReference/" + g, BM_PerceptionTags, g, R)->Iterations(300);
    reg("BM_PerceptionEq1/" + g, BM_PerceptionEq1, g)->Iterations(600);
    if (g == "far" || g == "viewpoint" || g == "recorded") {
      reg("BM_PerceptionStairs/" + g, BM_PerceptionStairs, g)->Iterations(600);
    }
    if (g == "viewpoint" || g == "recorded") {
      reg("BM_PerceptionAruco/" + g, BM_PerceptionAruco, g, F)->Iterations(200);
      reg("BM_PerceptionArucoReference/" + g, BM_PerceptionAruco, g, R)->Iterations(100);
      reg("BM_PerceptionPnP/" + g, BM_PerceptionPnP, g)->Iterations(600);
    }
    if (g == "approach" || g == "close") reg("BM_PerceptionPnP/" + g, BM_PerceptionPnP, g)->Iterations(600);
  }
  reg("BM_PerceptionTracking", BM_PerceptionTracking, F)->Iterations(600);
  reg("BM_PerceptionTrackingReference", BM_PerceptionTracking, R)->Iterations(300);
  reg("BM_PerceptionControl", BM_PerceptionControl)->Iterations(2000);
  const std::vector<std::string> conditions =
      recorded ? std::vector<std::string>{"recorded"} : std::vector<std::string>{"nominal", "dim", "bright", "behind"};
  for (const std::string& c : conditions) {
    // FindShelf sees one frame per synthetic sequence (the viewpoint shows the whole shelf);
    // the "far" stills time its perception stage by stage instead.
    for (const std::string p : {"search", "viewpoint", "inventory", "approach"}) {
      if (p == std::string("search") && !recorded) continue;
      const int n = p == "approach" ? 400 : 60;
      reg("BM_Step/" + c + "/" + p, BM_Step, c, std::string(p), F)->Iterations(n);
      if (c == "nominal" && (p == "inventory" || p == "approach")) {
        reg("BM_StepReference/" + c + "/" + p, BM_Step, c, std::string(p), R)->Iterations(p == "approach" ? 200 : 30);
      }
    }
  }
  for (const std::string& g : groups) reg("BM_Baseline/" + g, BM_Baseline, g)->Iterations(g == "far" ? 40 : 200);
  return true;
}();

}  // namespace
}  // namespace shelfcross::bench
