// Renderers started and torn down in parallel threads, as a campaign's worker threads and the
// co-simulations of one process do (once a general protection fault in Mesa's
// swrast_dri.so once took down a campaign). Every round, several threads start together,
// each creates its renderer (its own EGL context on the shared display), renders one frame,
// compares it with the reference frame byte for byte, destroys the renderer and exits; the
// rounds follow one another immediately, so that the last renderer of a round goes while the
// next round's are being made. Deterministic in its checks; the interleaving is the OS's.
#include <gtest/gtest.h>

#include <barrier>
#include <memory>
#include <thread>
#include <vector>

#include "render/renderer.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

CameraIntrinsics small_camera() {
  CameraIntrinsics c;  // a quarter of the Tello's picture: the test is about start-up, not pixels
  c.width_px = 240;
  c.height_px = 180;
  c.fx_px /= 4;
  c.fy_px /= 4;
  c.cx_px /= 4;
  c.cy_px /= 4;
  return c;
}

TEST(RendererThreads, ParallelStartUpAndTeardownGiveTheReferenceFrame) {
  const Warehouse warehouse = test::paper_test_shelf();
  const Eigen::Isometry3d X_WC = test::camera_looking_forward(Eigen::Vector3d(1.6, 0.2, 0.9));
  cv::Mat reference;
  {
    Renderer r(warehouse, small_camera());
    reference = r.render(X_WC).clone();
  }  // no renderer left: the first round starts from an idle display, as a new process does
  constexpr int kThreads = 4, kRounds = 8;
  std::vector<std::vector<cv::Mat>> frames(kRounds, std::vector<cv::Mat>(kThreads));
  std::vector<std::unique_ptr<std::barrier<>>> starts;
  std::vector<std::thread> previous;
  for (int round = 0; round < kRounds; ++round) {
    starts.push_back(std::make_unique<std::barrier<>>(kThreads));
    std::barrier<>& start = *starts.back();
    std::vector<std::thread> threads;
    for (int k = 0; k < kThreads; ++k) {
      threads.emplace_back([&frames, &start, &warehouse, &X_WC, round, k] {
        start.arrive_and_wait();
        Renderer r(warehouse, small_camera());
        frames[round][k] = r.render(X_WC).clone();
      });
    }
    // The previous round's threads are joined only now: their teardown overlaps this start-up.
    for (std::thread& t : previous) t.join();
    previous = std::move(threads);
  }
  for (std::thread& t : previous) t.join();
  for (int round = 0; round < kRounds; ++round) {
    for (int k = 0; k < kThreads; ++k) {
      const cv::Mat& f = frames[round][k];
      ASSERT_EQ(f.size(), reference.size()) << "round " << round << ", thread " << k;
      EXPECT_TRUE(std::equal(reference.datastart, reference.dataend, f.datastart)) << "round " << round << ", thread " << k;
    }
  }
}

// Renderers made, used and destroyed on a thread that exits right after, while this thread
// makes, uses and destroys its own: the display's last user and its next first user overlap
// in every order, with a thread that used the driver exiting meanwhile (egl_context.cpp,
// release_display).
TEST(RendererThreads, RenderersGoingOnExitingThreadsWhileOthersStart) {
  const Warehouse warehouse = test::paper_test_shelf();
  const Eigen::Isometry3d X_WC = test::camera_looking_forward(Eigen::Vector3d(1.6, 0.2, 0.9));
  const cv::Mat reference = Renderer(warehouse, small_camera()).render(X_WC).clone();
  constexpr int kRounds = 16;
  for (int round = 0; round < kRounds; ++round) {
    cv::Mat theirs;
    std::thread exiting([&] { theirs = Renderer(warehouse, small_camera()).render(X_WC).clone(); });
    const cv::Mat ours = Renderer(warehouse, small_camera()).render(X_WC).clone();
    exiting.join();
    for (const cv::Mat* f : {&ours, const_cast<const cv::Mat*>(&theirs)}) {
      ASSERT_EQ(f->size(), reference.size()) << "round " << round;
      ASSERT_TRUE(std::equal(reference.datastart, reference.dataend, f->datastart)) << "round " << round;
    }
  }
}

}  // namespace
}  // namespace shelfcross::render
