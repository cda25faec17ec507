#pragma once
// The perception benchmark's frame set: a fixed, versioned list of camera poses and
// conditions over a scenario (by default scenarios/paper_test_shelf.yaml), rendered by the
// co-simulation's renderer at the scenario's 960 x 720 camera. One library (shelfcross::frames)
// for `shelfcross frames` (app/cmd_frames.cpp), which writes the set, and the benchmark
// (bench/perception_bench.cpp), which reads it or writes it on first use.
//
// Versions: 1, the first renderer (undistorted pinhole render + bilinear lens
// remap); 2, the lens in the geometry, point-sampled at pixel centres: edge pixels
// change (measured on four poses of the test shelf: 1.4-5.1 % of pixels differ, mean absolute
// difference 0.18-0.62 grey levels, all within 2 px of an edge but for the old renderer's
// darkened top row and right column, where its remap sampled past its render); 3, the
// adaptive lens grid (lens_mesh.hpp: a k-d tree of cells, large where the lens bends little):
// faces are split at other places, so drawn edges move by up to the chord tolerance (0.25 px)
// and edge pixels change: over the 428 noise-free frames, 186,239 of 295.8 million pixels
// (0.063 %; at most 0.12 % of one frame) differ from version 2, 98.9 % of them within 2 px of
// an edge, each a pixel centre that changed face (differences up to 202 grey levels; mean
// absolute difference over all pixels 0.033). `--check` gives the same decisions as on
// version 2; 4, the room, shelves and boxes meshed along their own edges instead of the lens
// grid (lens_mesh.hpp, edge_mesh.hpp): drawn edges move within the same tolerance, so edge
// pixels change (how many: docs/performance.md, the renderer's triangles), and `--check`
// gives the same decisions.
//
// What the set holds (kFrameSetVersion 4). For each condition (nominal light; dim, light x0.5;
// bright, light x1.6; behind: a second shelf 1.2 m behind shelf 0 with boxes in every cell
// that is empty on shelf 0, so its tags and markers show through the front shelf's empty
// cells), one video sequence at 30 fps:
//   steps 0..kViewpointFrames-1   hovering at the optimal viewpoint (flight_sw::
//                                 optimal_viewpoint_G), a few mm and mrad of deterministic
//                                 jitter: group "viewpoint"
//   then kApproachFrames frames   a straight line from the viewpoint to kApproachEndRange_m in
//                                 front of the target cell (about 0.5 m/s, twice the flight
//                                 software's forward speed), heading turning toward the cell
//                                 centre at up to kApproachYawRate_radps: group
//                                 "approach" while the camera is farther than kCloseRange_m
//                                 from the tag plane, "close" nearer (corner tags leave the
//                                 view at the end)
// plus, nominal only, stills of group "far" (FindShelf: 3 and 4.2 m away, a shelf half out of
// view, a bare wall). The target cell is the empty cell the flight software picks (the one
// whose corner tags' centroid projects nearest the principal point from the viewpoint).
//
// Files: <dir>/manifest.csv and one noise-free PNG per frame (PNG keeps flat renders small).
// The loader adds the sensor noise of the scenario's cosim.render_noise_stddev with
// render::SensorNoise and the frame's seed: the very image the renderer would have produced
// with that noise, as the co-simulation feeds the flight software. The manifest's header
// names the version and a hash of the scenario; a mismatch means "regenerate".
// Deterministic: same scenario, same code, same machine and driver give the same images.

#include <algorithm>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "flight_sw/mission/flight_software.hpp"
#include "sdk/command.hpp"
#include "shelfcross/cell_index.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::frames {

inline constexpr int kFrameSetVersion = 4;
inline constexpr std::int64_t kFrameRateHz = 30;
inline constexpr int kViewpointFrames = 6;
inline constexpr int kApproachFrames = 100;
/// Heading rate limit on the approach path (the flight software commands at most 0.8 rad/s).
inline constexpr double kApproachYawRate_radps = 0.5;
inline constexpr double kApproachEndRange_m = 0.42;  ///< camera to the tag plane, last frame
inline constexpr double kCloseRange_m = 0.80;        ///< "close" below this range

/// A lighting / scene variant of the scenario.
struct Condition {
  const char* name;
  double light_scale;
  bool shelf_behind;
};

const std::vector<Condition>& frame_conditions();

struct FrameSpec {
  std::string name;       ///< file stem, unique
  std::string group;      ///< far | viewpoint | approach | close
  std::string condition;  ///< nominal | dim | bright | behind
  int step = -1;          ///< index in its condition's video sequence; -1 for a still
  Eigen::Vector3d p_WB_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  double range_m = 0.0;  ///< camera to shelf 0's tag plane along its normal
  std::uint64_t noise_seed = 0;
};

struct Frame {
  FrameSpec spec;
  cv::Mat bgr;  ///< with sensor noise
};

struct FrameSet {
  std::string source;  ///< directory read
  std::vector<Frame> frames;
  /// Frames of one condition's sequence, in step order.
  std::vector<const Frame*> sequence(const std::string& condition) const {
    std::vector<const Frame*> s;
    for (const Frame& f : frames) {
      if (f.spec.condition == condition && f.spec.step >= 0) s.push_back(&f);
    }
    std::sort(s.begin(), s.end(), [](const Frame* a, const Frame* b) { return a->spec.step < b->spec.step; });
    return s;
  }
  std::vector<const Frame*> group(const std::string& group) const {
    std::vector<const Frame*> s;
    for (const Frame& f : frames) {
      if (f.spec.group == group) s.push_back(&f);
    }
    return s;
  }
};

/// The scenario of one condition: shelf 0 untouched, light scaled, maybe a shelf behind.
verification::Scenario condition_scenario(const verification::Scenario& base, const Condition& c);

/// FNV-1a of the scenario's fully written form.
std::string scenario_hash(const verification::Scenario& s);

/// Camera range to the tag plane of shelf 0 for a body pose (along the shelf normal).
double range_to_tags_m(const verification::Scenario& sc, const flight_sw::FlightConfig& config,
                       const Eigen::Vector3d& p_WB_m, double yaw_rad);

/// The target cell: among shelf 0's empty cells the vehicle fits through, the one whose
/// corner tags' centroid projects nearest the principal point from camera pose X_WC. Throws
/// std::runtime_error when shelf 0 has no crossable empty cell.
CellIndex expected_target(const verification::Scenario& sc, const flight_sw::FlightConfig& config,
                          const Eigen::Isometry3d& X_WC);

/// The frame list for a scenario (no rendering). Throws std::runtime_error on a scenario
/// without a shelf.
std::vector<FrameSpec> frame_specs(const verification::Scenario& sc);

// ---- Files ----

std::string manifest_header(const verification::Scenario& sc);

/// Why the set in `dir` cannot be used for `sc` (missing, other version or scenario), or empty.
std::optional<std::string> frame_set_stale(const std::filesystem::path& dir, const verification::Scenario& sc);

/// Renders the set of `sc` into `dir` (created). `only_condition` non-empty: that condition's
/// sequence only (and the far stills if nominal). Returns the number of frames written.
/// Throws std::runtime_error when a frame cannot be written.
int generate_frame_set(const verification::Scenario& sc, const std::filesystem::path& dir,
                       const std::string& only_condition = "");

/// Reads a set written by generate_frame_set for `sc` (throws std::runtime_error if stale).
FrameSet load_frame_set(const std::filesystem::path& dir, const verification::Scenario& sc);

/// A folder of recorded images (png, jpg, jpeg, bmp; sorted by name) as one sequence of
/// condition and group "recorded"; images of another size are resized to width x height.
/// Throws std::runtime_error on an unreadable image or a folder without images.
FrameSet load_image_folder(const std::filesystem::path& dir, int width_px, int height_px);

// ---- Driving the flight software with a sequence ----

/// Feeds a FlightSoftware as the co-simulation would, without a vehicle: the opening
/// exchange (every non-rc command answered "ok" 20 ms later), then frames at kFrameRateHz in
/// order. Only frame() is the flight software's per-frame step; replies due before a frame are
/// handed over first, outside it (prepare()), so a caller can time the frame step alone.
class SequenceDriver {
 public:
  explicit SequenceDriver(const flight_sw::FlightConfig& config) : fsw_(config) {
    handle(fsw_.start(0));
    while (fsw_.phase() != flight_sw::Phase::WaitVideo && !fsw_.finished() && t_ns_ < seconds_to_ns(5.0)) {
      t_ns_ += 10'000'000;
      prepare();
      handle(fsw_.step(flight_sw::ClockTick{t_ns_}));
    }
  }
  /// Advances to the next frame time and hands over the replies due by then.
  const CameraFrame& prepare_frame(const cv::Mat& bgr) {
    ++k_;
    t_ns_ = std::max(t_ns_, tick_time_ns(k_, kFrameRateHz));
    prepare();
    frame_.t_ns = t_ns_;
    frame_.index = k_;
    frame_.bgr = bgr;
    return frame_;
  }
  /// The step on the prepared frame.
  void step_frame() { handle(fsw_.step(frame_)); }
  flight_sw::FlightSoftware& fsw() { return fsw_; }

 private:
  void prepare() {
    while (!replies_.empty() && replies_.front().t_ns <= t_ns_) {
      const SdkReply r = replies_.front();
      replies_.pop_front();
      handle(fsw_.step(r));
    }
  }
  void handle(const std::vector<SdkCommand>& commands) {
    for (const SdkCommand& c : commands) {
      if (!sdk::is_rc_text(c.text)) replies_.push_back({c.t_ns + 20'000'000, "ok"});
    }
  }
  flight_sw::FlightSoftware fsw_;
  TimeNs t_ns_ = 0;
  std::int64_t k_ = 0;
  std::deque<SdkReply> replies_;
  CameraFrame frame_;
};

/// Plays one sequence to a fresh flight software as a flight would go: the viewpoint frames
/// (group "viewpoint") cycled while it searches, goes to the viewpoint and takes the inventory
/// (at most kMaxViewpointSteps), then every other frame in order until it is done.
class SequencePlayer {
 public:
  static constexpr int kMaxViewpointSteps = 60;
  SequencePlayer(const flight_sw::FlightConfig& config, const std::vector<const Frame*>& sequence)
      : config_(config) {
    for (const Frame* f : sequence) (f->spec.group == "viewpoint" ? viewpoint_ : rest_).push_back(f);
    restart();
  }
  void restart() {
    driver_.emplace(config_);
    viewpoint_steps_ = 0;
    next_rest_ = 0;
  }
  /// The next frame (already prepared on the driver: call driver().step_frame()), or nullptr
  /// when the sequence is over.
  const Frame* next() {
    using flight_sw::Phase;
    const Phase p = driver_->fsw().phase();
    const bool before_approach = p == Phase::WaitVideo || p == Phase::TakeOff || p == Phase::FindShelf ||
                                 p == Phase::GoToViewpoint || p == Phase::TakeInventory;
    const Frame* f = nullptr;
    if (driver_->fsw().finished()) return nullptr;
    if (!viewpoint_.empty() && before_approach && viewpoint_steps_ < kMaxViewpointSteps) {
      f = viewpoint_[static_cast<size_t>(viewpoint_steps_++) % viewpoint_.size()];
    } else if (next_rest_ < rest_.size()) {
      f = rest_[next_rest_++];
    } else {
      return nullptr;
    }
    driver_->prepare_frame(f->bgr);
    return f;
  }
  SequenceDriver& driver() { return *driver_; }

 private:
  flight_sw::FlightConfig config_;
  std::vector<const Frame*> viewpoint_, rest_;
  std::optional<SequenceDriver> driver_;
  int viewpoint_steps_ = 0;
  size_t next_rest_ = 0;
};

}  // namespace shelfcross::frames
