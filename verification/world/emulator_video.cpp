#include "verification/world/emulator_video.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/core/mat.hpp>

#include "render/ground_truth.hpp"
#include "sdk/video_framing.hpp"
#include "verification/world/h264_encoder.hpp"
#include "verification/world/mission_setup.hpp"

namespace shelfcross::verification {
namespace {

/// Captures from one key frame to the next: the setting, or one second of captures.
std::int64_t key_interval_captures(const EmulatorConfig& config, const Scenario& scenario) {
  return config.key_interval_frames > 0 ? config.key_interval_frames
                                        : std::max<std::int64_t>(1, std::llround(scenario.frame_rate_hz));
}

}  // namespace

/// The renderer (the worker's own; inline video uses the co-simulation's) and the encoder.
struct EmulatorVideo::Coder {
  Coder(const Scenario& sc, int key_interval_frames, int slices, bool own_renderer)
      : renderer(own_renderer ? std::make_unique<render::Renderer>(sc.warehouse, sc.camera, render_options_for(sc))
                              : nullptr),
        // The emulator forces every key frame (by capture time); the encoder's own interval
        // is a backstop far beyond it.
        encoder(sc.camera.width_px, sc.camera.height_px, std::max(1, static_cast<int>(std::lround(sc.frame_rate_hz))),
                4 * (key_interval_frames > 0 ? key_interval_frames
                                             : std::max(1, static_cast<int>(std::lround(sc.frame_rate_hz)))),
                H264Encoder::kTelloQp, std::min(slices, (sc.camera.height_px + 15) / 16)),
        motion_blur(sc.cosim.motion_blur_samples > 1) {}
  std::unique_ptr<render::Renderer> renderer;
  H264Encoder encoder;
  bool motion_blur;
  cv::Mat bgr;
};

EmulatorVideo::EmulatorVideo(const Scenario& scenario, const EmulatorConfig& config, render::Renderer* inline_renderer,
                             EmulatorOutbox& outbox)
    : scenario_(scenario), config_(config), outbox_(outbox), inline_renderer_(inline_renderer) {
  if (inline_renderer_) {
    coder_ = std::make_unique<Coder>(scenario_, config_.key_interval_frames, config_.slices_per_frame, false);
    renderer_description_ = inline_renderer_->backend_description();
    return;
  }
  start_worker();
}

void EmulatorVideo::start_worker() {
  // The renderer's EGL context is made current on the thread that creates it, and a context
  // is current on one thread at a time: the worker creates (and alone uses) the renderer.
  worker_ = std::thread([this] { worker_loop(); });
  std::unique_lock lock = outbox_.lock();
  job_ready_.wait(lock, [this] { return handoff_.ready; });
  if (!coder_) {
    const std::string why = handoff_.error;
    lock.unlock();
    worker_.join();
    throw std::runtime_error("tello emulator video: " + why);
  }
}

EmulatorVideo::~EmulatorVideo() {
  {
    const auto lock = outbox_.lock();
    handoff_.stop = true;
  }
  job_ready_.notify_all();
  if (worker_.joinable()) worker_.join();
}

const std::string& EmulatorVideo::error_locked() const { return handoff_.error; }

void EmulatorVideo::capture(const TelloWorld::Capture& capture, TimeNs t, TimeNs now_ns,
                            const std::optional<tello::Endpoint>& to) {
  if (!to) {
    was_on_ = false;  // the next streamon starts with a key frame
    return;
  }
  const TimeNs frame_period_ns = capture.period_ns;
  const auto lock = outbox_.lock();
  EmulatorCounters& counters = outbox_.counters_locked();
  ++counters.frames_captured;
  const bool stalled = outbox_.faults_locked().video_stalled(t);
  const bool lost = outbox_.faults_locked().frame_lost();  // drawn for every capture, stalled or not
  if (stalled) {
    ++counters.frames_stalled;
  } else if (lost) {
    ++counters.frames_lost;
  } else if (!inline_renderer_ && now_ns - t > frame_period_ns) {
    ++counters.frames_dropped_late;
  } else if (handoff_.busy || handoff_.job) {
    ++counters.frames_dropped_busy;
  } else {
    // Key frames by capture time, not by frames encoded: frames dropped here (renderer
    // busy) must not stretch the group of pictures past its interval, as they would
    // if the encoder counted (the Tello's encoder sees every frame).
    const bool key = !was_on_ || capture.index >= next_key_capture_;
    if (key) next_key_capture_ = capture.index + key_interval_captures(config_, scenario_);
    const FrameJob job{capture.index, t, capture.X_WC_prev, capture.X_WC, capture.X_WC_readout_start,
                       capture.noise_seed, key, *to};
    was_on_ = true;
    if (inline_renderer_) {
      // The co-simulation: rendered and encoded now, in simulated time (an encoding
      // error is a failure of the run, not a dropped frame).
      EncodedFrame frame = encode(*coder_, *inline_renderer_, job);
      outbox_.send_frame_locked(job.t_ns, std::move(frame.datagrams), frame.key, job.to, now_ns);
    } else {
      handoff_.job = job;
      job_ready_.notify_one();
    }
  }
}

void EmulatorVideo::worker_loop() {
  {
    std::unique_ptr<Coder> coder;
    std::string error;
    try {
      coder = std::make_unique<Coder>(scenario_, config_.key_interval_frames, config_.slices_per_frame, true);
      renderer_description_ = coder->renderer->backend_description();
    } catch (const std::exception& e) {
      error = e.what();
    }
    const auto lock = outbox_.lock();
    coder_ = std::move(coder);
    handoff_.error = error;
    handoff_.ready = true;
    job_ready_.notify_all();
    if (!coder_) return;
  }
  for (;;) {
    FrameJob job;
    {
      std::unique_lock lock = outbox_.lock();
      job_ready_.wait(lock, [this] { return handoff_.stop || handoff_.job.has_value(); });
      if (handoff_.stop) {
        // The renderer's EGL context is destroyed on the thread it is current on: another
        // thread's eglDestroyContext could only defer it (and the context would leak).
        coder_.reset();
        return;
      }
      job = *handoff_.job;
      handoff_.job.reset();
      handoff_.busy = true;
    }
    EncodedFrame frame;
    std::string error;
    try {
      frame = encode(*coder_, *coder_->renderer, job);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const auto lock = outbox_.lock();
    handoff_.busy = false;
    if (!error.empty()) {
      handoff_.error = "video: " + error;
      continue;
    }
    // Sends what is due by the capture time: the frame itself unless delayed (the worker has
    // no clock; the main loop sends delayed datagrams when they fall due).
    outbox_.send_frame_locked(job.t_ns, std::move(frame.datagrams), frame.key, job.to, job.t_ns);
  }
}

EmulatorVideo::EncodedFrame EmulatorVideo::encode(Coder& coder, render::Renderer& renderer, const FrameJob& job) {
  if (coder.motion_blur) {
    renderer.render_blurred_rolling_into(job.X_WC_prev, job.X_WC_readout_start, job.X_WC, job.noise_seed, coder.bgr);
  } else {
    renderer.render_rolling_into(job.X_WC_readout_start, job.X_WC, job.noise_seed, coder.bgr);
  }
  const std::string access_unit = coder.encoder.encode(coder.bgr, job.force_key);
  const std::vector<int> types = sdk::nal_unit_types(access_unit);
  EncodedFrame frame;
  frame.key = std::find(types.begin(), types.end(), 5) != types.end();
  frame.datagrams = sdk::tello_datagrams(access_unit);
  return frame;
}

}  // namespace shelfcross::verification
