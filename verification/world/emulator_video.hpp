#pragma once
// The Tello emulator's camera stream: which captures are encoded and sent (none inside the
// injected stall, none of a frame the faults lose, none the worker is too late or too busy
// for), the key frames by capture index (one per key interval of captures, and the first
// after streamon), and the rendering and encoding itself. In the co-simulation every capture
// is rendered by the caller's renderer and encoded inline, in simulated time; under tello-sim
// a worker thread owns the renderer (its EGL context is current on the thread that made it)
// and the encoder, and takes one capture at a time. The worker shares the outbox's mutex.
// Internal to the emulator (tello_emulator.cpp).

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "render/renderer.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/emulator_outbox.hpp"
#include "verification/world/tello_world.hpp"

namespace shelfcross::verification {

class EmulatorVideo {
 public:
  /// `scenario`, `config` and `outbox` outlive it. inline_renderer: the co-simulation's (made for the scenario's warehouse and camera,
  /// used from the calling thread only); null: starts the worker thread and waits until it
  /// has built its renderer and encoder. Throws std::runtime_error when it could not (no EGL,
  /// no libx264), and what H264Encoder throws for the inline encoder.
  EmulatorVideo(const Scenario& scenario, const EmulatorConfig& config, render::Renderer* inline_renderer,
                EmulatorOutbox& outbox);
  ~EmulatorVideo();  ///< stops and joins the worker
  EmulatorVideo(const EmulatorVideo&) = delete;
  EmulatorVideo& operator=(const EmulatorVideo&) = delete;

  /// A capture due at the tick t (now_ns: the time the main loop has reached); `to`: the
  /// client's video port while the stream is on, nullopt while it is off (the next capture
  /// streamed is then a key frame). Draws the frame-loss fault of every streamed capture.
  void capture(const TelloWorld::Capture& capture, TimeNs t, TimeNs now_ns,
               const std::optional<tello::Endpoint>& to);
  /// Why the worker could not render or encode a frame ("video: ..."), empty while it can.
  /// Requires the outbox's lock.
  const std::string& error_locked() const;
  /// "EGL ... GL_RENDERER ..." of the renderer in use.
  const std::string& renderer_description() const { return renderer_description_; }

 private:
  struct Coder;
  struct FrameJob {
    std::int64_t index = 0;
    TimeNs t_ns = 0;
    Eigen::Isometry3d X_WC_prev = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_WC_readout_start = Eigen::Isometry3d::Identity();
    std::uint64_t noise_seed = 0;
    bool force_key = false;
    tello::Endpoint to;
  };
  /// The capture handed to the worker and the worker's state (under the outbox's mutex).
  struct Handoff {
    std::optional<FrameJob> job;
    bool busy = false;   ///< the worker renders or encodes a frame
    bool stop = false;
    bool ready = false;  ///< the worker has built its renderer and encoder (or failed)
    /// Why the worker could not build them (the constructor throws it), or later could not
    /// render or encode a frame ("video: ...").
    std::string error;
  };
  struct EncodedFrame {
    std::vector<std::string> datagrams;
    bool key = false;  ///< holds an IDR picture
  };
  void start_worker();
  void worker_loop();
  /// Renders, encodes and cuts one capture into datagrams (the worker's job, or inline).
  static EncodedFrame encode(Coder& coder, render::Renderer& renderer, const FrameJob& job);

  const Scenario& scenario_;
  const EmulatorConfig& config_;
  EmulatorOutbox& outbox_;
  render::Renderer* inline_renderer_;
  bool was_on_ = false;  ///< a capture went to the encoder since the stream last came on
  std::int64_t next_key_capture_ = 0;  ///< the capture index due for the next key frame
  std::condition_variable job_ready_;
  Handoff handoff_;
  std::string renderer_description_;
  std::unique_ptr<Coder> coder_;
  std::thread worker_;
};

}  // namespace shelfcross::verification
