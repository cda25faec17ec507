// Renderer throughput at 960 x 720 on one core with llvmpipe.
//
// Run: taskset -c 1 build/release/bench/shelfcross_bench --benchmark_filter=Render
// LP_NUM_THREADS=1 is set here before the first EGL display is created (llvmpipe reads it
// when its screen is created) and OpenCV runs single-threaded, so the figure is one core's
// worth of work. Times are process CPU time (all threads: llvmpipe's rasteriser thread
// included), which also keeps the figure meaningful on a loaded machine; frames per second
// = 1 / CPU time per frame.
//
// BM_RenderFrame/supersample:S/noise:N is the whole Renderer::render_into (lens mesh + upload
// + draw + readback [+ S x S block average] + RGBA->BGR [+ noise]) with the default lens and
// lighting; noise:1 is the co-simulation's default sensor noise (cosim.render_noise_stddev,
// 2 grey levels), the configuration the renderer's frame budget is set for. BM_RenderMeshOnly and
// BM_RenderFinishOnly time two CPU stages alone: the per-frame lens mesh (cull, clip, split,
// project) and the fused RGBA->BGR + noise pass; draw + readback is the rest.
// BM_RenderFrameRolling/turning:1 is a rolling-shutter frame (see below), turning:0 the same
// renderer held still.
#include <benchmark/benchmark.h>

#include <cstdlib>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "render/lens_mesh.hpp"
#include "render/noise.hpp"
#include "render/renderer.hpp"
#include "render/rolling_shutter.hpp"
#include "render/test/test_warehouse.hpp"

namespace {

using shelfcross::CameraIntrinsics;
using shelfcross::render::Renderer;
using shelfcross::render::RenderOptions;

constexpr double kDefaultNoise = 2.0;  // verification/scenario/cosim_settings.hpp render_noise_stddev

Renderer& bench_renderer(int supersample, bool noise) {
  ::setenv("LP_NUM_THREADS", "1", 1);
  cv::setNumThreads(1);
  auto make = [](int s, bool n) {
    RenderOptions o;
    o.supersample = s;
    o.noise_stddev = n ? kDefaultNoise : 0.0;
    return o;
  };
  static Renderer r10(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{}, make(1, false));
  static Renderer r11(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{}, make(1, true));
  static Renderer r20(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{}, make(2, false));
  if (supersample == 1) return noise ? r11 : r10;
  return r20;
}

Eigen::Isometry3d bench_pose() {
  return shelfcross::render::test::camera_looking_forward({0.8, 0.0, 0.98});
}

void BM_RenderFrame(benchmark::State& state) {
  Renderer& r = bench_renderer(static_cast<int>(state.range(0)), state.range(1) != 0);
  state.SetLabel(r.gl_renderer_name());
  cv::Mat bgr;
  std::uint64_t seed = 0;
  r.render_into(bench_pose(), seed, bgr);
  for (auto _ : state) {
    r.render_into(bench_pose(), ++seed, bgr);
    benchmark::DoNotOptimize(bgr.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrame)->Args({1, 1})->Args({1, 0})->Args({2, 0})
    ->ArgNames({"supersample", "noise"})->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

void BM_RenderMeshOnly(benchmark::State& state) {
  // A copy of the renderer's mesher (its faces and lens grid), rebuilt for the frame's pose.
  shelfcross::render::LensMesher mesher = bench_renderer(1, true).lens_mesh();
  for (auto _ : state) {
    mesher.build(bench_pose());
    benchmark::DoNotOptimize(mesher.vertices().data());
  }
  state.counters["vertices"] = static_cast<double>(mesher.vertices().size());
  state.counters["triangles"] = static_cast<double>(mesher.indices().size() / 3);
}
BENCHMARK(BM_RenderMeshOnly)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

// A rolling-shutter frame (render_rolling_into): the camera turning at 0.5 rad/s over a 20 ms
// readout, with the sensor noise, on a renderer whose faces are clipped
// rolling_shutter_margin_px = 47 px outside the image: the margin
// render_options_for gives a scenario whose readout may reach the 30 fps frame period
// (fx 921 px x 3 rad/s x 33.3 ms / 2). turning:0 is the same renderer held still (the global
// shutter's path, with the wider margin).
Renderer& rolling_bench_renderer() {
  ::setenv("LP_NUM_THREADS", "1", 1);
  cv::setNumThreads(1);
  static Renderer r(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{}, [] {
    RenderOptions o;
    o.noise_stddev = kDefaultNoise;
    o.rolling_shutter_margin_px = 47.0;
    return o;
  }());
  return r;
}

void BM_RenderFrameRolling(benchmark::State& state) {
  Renderer& r = rolling_bench_renderer();
  const bool turning = state.range(0) != 0;
  const Eigen::Isometry3d X_end = bench_pose();
  const Eigen::Isometry3d X_start =
      turning ? shelfcross::render::test::camera_looking_forward({0.8, 0.0, 0.98}, -0.5 * 0.020) : X_end;
  state.SetLabel(r.gl_renderer_name());
  cv::Mat bgr;
  std::uint64_t seed = 0;
  r.render_rolling_into(X_start, X_end, seed, bgr);
  for (auto _ : state) {
    r.render_rolling_into(X_start, X_end, ++seed, bgr);
    benchmark::DoNotOptimize(bgr.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrameRolling)->Arg(1)->Arg(0)->ArgName("turning")->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);

// The rolling frame's mesh alone: BM_RenderMeshOnly's, with the 47 px margin of
// rolling_bench_renderer, meshed at the middle pose of BM_RenderFrameRolling/turning:1's
// readout and each vertex moved to its row's pose.
void BM_RenderMeshOnlyRolling(benchmark::State& state) {
  shelfcross::render::LensMesher mesher = rolling_bench_renderer().lens_mesh();
  const shelfcross::render::ReadoutPoses readout(
      shelfcross::render::test::camera_looking_forward({0.8, 0.0, 0.98}, -0.5 * 0.020), bench_pose());
  for (auto _ : state) {
    mesher.build(readout);
    benchmark::DoNotOptimize(mesher.vertices().data());
  }
  state.counters["vertices"] = static_cast<double>(mesher.vertices().size());
  state.counters["triangles"] = static_cast<double>(mesher.indices().size() / 3);
}
BENCHMARK(BM_RenderMeshOnlyRolling)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

void BM_RenderFinishOnly(benchmark::State& state) {
  cv::setNumThreads(1);
  const shelfcross::render::SensorNoise noise(720, 960, 3, kDefaultNoise);
  cv::Mat src(720, 960, CV_8UC4, cv::Scalar(90, 120, 150, 255)), dst;
  std::uint64_t seed = 0;
  for (auto _ : state) {
    noise.apply_rgba_to_bgr(src, dst, ++seed);
    benchmark::DoNotOptimize(dst.data);
  }
}
BENCHMARK(BM_RenderFinishOnly)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

}  // namespace
