// Renderer throughput at 960 x 720 on one core with llvmpipe.
//
// Run: build/release/bench/shelfcross_bench --benchmark_filter=Render
// LP_NUM_THREADS=1 is set here before the first EGL display is created (llvmpipe reads it
// when its screen is created) and OpenCV runs single-threaded, so the figure is one core's
// worth of work. Times are process CPU time (all threads: llvmpipe's rasteriser thread
// included), which also keeps the figure meaningful on a loaded machine; frames per second
// = 1 / CPU time per frame.
//
// BM_RenderFrame is the whole Renderer::render_into (draw + readback + distortion remap +
// RGBA->BGR); BM_RenderRemapOnly and BM_RenderConvertOnly time the CPU stages alone on the
// same buffers, so draw + readback = RenderFrame - RemapOnly - ConvertOnly.
#include <benchmark/benchmark.h>

#include <cstdlib>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "render/renderer.hpp"
#include "render/test/test_warehouse.hpp"

namespace {

using shelfcross::CameraIntrinsics;
using shelfcross::render::Renderer;
using shelfcross::render::RenderOptions;

Renderer& bench_renderer(int supersample) {
  ::setenv("LP_NUM_THREADS", "1", 1);
  cv::setNumThreads(1);
  static Renderer r1(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{});
  if (supersample == 1) return r1;
  static Renderer r2(shelfcross::render::test::paper_test_shelf(), CameraIntrinsics{}, [] {
    RenderOptions o;
    o.supersample = 2;
    return o;
  }());
  return r2;
}

Eigen::Isometry3d bench_pose() {
  return shelfcross::render::test::camera_looking_forward({0.8, 0.0, 0.98});
}

void BM_RenderFrame(benchmark::State& state) {
  Renderer& r = bench_renderer(static_cast<int>(state.range(0)));
  state.SetLabel(r.gl_renderer_name());
  cv::Mat bgr;
  r.render_into(bench_pose(), 0, bgr);
  for (auto _ : state) {
    r.render_into(bench_pose(), 0, bgr);
    benchmark::DoNotOptimize(bgr.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrame)->Arg(1)->Arg(2)->ArgName("supersample")->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);

void BM_RenderRemapOnly(benchmark::State& state) {
  Renderer& r = bench_renderer(1);
  const auto& rc = r.render_camera();
  cv::Mat src(rc.height_px, rc.width_px, CV_8UC4, cv::Scalar(90, 120, 150, 255)), dst, m1, m2;
  cv::convertMaps(rc.map_xy, cv::noArray(), m1, m2, CV_16SC2);
  for (auto _ : state) {
    cv::remap(src, dst, m1, m2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    benchmark::DoNotOptimize(dst.data);
  }
}
BENCHMARK(BM_RenderRemapOnly)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

void BM_RenderConvertOnly(benchmark::State& state) {
  cv::Mat src(720, 960, CV_8UC4, cv::Scalar(90, 120, 150, 255)), dst;
  cv::setNumThreads(1);
  for (auto _ : state) {
    cv::cvtColor(src, dst, cv::COLOR_RGBA2BGR);
    benchmark::DoNotOptimize(dst.data);
  }
}
BENCHMARK(BM_RenderConvertOnly)->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

}  // namespace
