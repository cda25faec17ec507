// Camera frames per second at 960 x 720 on one core with llvmpipe (LP_NUM_THREADS=1): the
// whole render() (rasterise, read back, lens distortion remap, BGR), the paper's test shelf
// seen from the approach.
//   build/release/bench/shelfcross_bench --benchmark_filter=Render
#include <cstdlib>

#include <benchmark/benchmark.h>

#include "render/renderer.hpp"
#include "verification/scenario.hpp"

namespace {

using namespace shelfcross;

void BM_RenderFrame(benchmark::State& state) {
  setenv("LP_NUM_THREADS", "1", 1);  // llvmpipe's rasteriser threads: one core
  const verification::Scenario s =
      verification::load_scenario(std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml");
  render::RenderOptions options;
  options.noise_stddev = state.range(0) ? 2.0 : 0.0;
  render::Renderer renderer(s.warehouse, s.camera, options);
  cv::Mat bgr;
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = rotation_body_from_camera(0.0);
  std::int64_t frame = 0;
  for (auto _ : state) {
    // Approaching from 2.5 m to 0.5 m in front of the face, at the height of level 2.
    X_WC.translation() = Eigen::Vector3d(0.5 + 2.0 * static_cast<double>(frame % 100) / 100.0, 0.0, 0.8);
    renderer.render_into(X_WC, static_cast<std::uint64_t>(frame++), bgr);
    benchmark::DoNotOptimize(bgr.data);
  }
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel(renderer.gl_renderer_name());
}
BENCHMARK(BM_RenderFrame)->Arg(0)->Arg(1)->ArgName("noise")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
