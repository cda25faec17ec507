#pragma once
// Decision equivalence of the fast and the reference perception pipelines (issue 7) on a
// sequence of the benchmark frame set: both flight softwares get the same inputs (the
// SequencePlayer's), and after every frame their phase, target, rc commands, full-view state
// and inventory so far must be equal, their SI velocity commands within kVelocityTolerance and
// their poses (when both have one) within kPoseTolerance_m / _rad. (The poses agree to about
// 1e-14: the same tag centroids go into the PnP.)

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "bench/frame_set.hpp"

namespace shelfcross::bench {

inline constexpr double kPoseTolerance_m = 0.002;
inline constexpr double kPoseTolerance_rad = 0.002;
/// SI velocity commands before their rounding to rc sticks (which must be equal).
inline constexpr double kVelocityTolerance = 1e-6;

struct PipelineComparison {
  bool same = true;
  int frames = 0;
  int poses_compared = 0;
  double max_pose_diff_m = 0.0;
  double max_pose_diff_rad = 0.0;
  std::string target;     ///< fast pipeline's target ("L3 C3", or "none")
  std::string inventory;  ///< fast pipeline's inventory JSON
  std::string phases;     ///< "phase@frame ..." of the fast pipeline
  std::string summary;    ///< one paragraph for people
};

inline PipelineComparison compare_pipelines(const FrameSet& set, const std::string& condition,
                                            flight_sw::FlightConfig config) {
  using flight_sw::PerceptionPipeline;
  config.perception.pipeline = PerceptionPipeline::fast;
  const std::vector<const Frame*> seq = set.sequence(condition);
  SequencePlayer fast(config, seq);
  config.perception.pipeline = PerceptionPipeline::reference;
  SequencePlayer reference(config, seq);
  PipelineComparison c;
  std::ostringstream why;
  std::optional<flight_sw::Phase> last_phase;
  const auto cell = [](const std::optional<flight_sw::CellIndex>& t) {
    return t ? "L" + std::to_string(t->level) + " C" + std::to_string(t->column) : std::string("none");
  };
  const auto box = [](const std::optional<cv::Rect2d>& r) {
    std::ostringstream os;
    if (r) os << "[" << r->x << ", " << r->y << ", " << r->width << " x " << r->height << "]";
    else os << "none";
    return os.str();
  };
  const auto fail = [&](const std::string& what) {
    if (c.same) {
      const flight_sw::Telemetry& ta = fast.driver().fsw().telemetry();
      const flight_sw::Telemetry& tb = reference.driver().fsw().telemetry();
      why << "  first difference at frame " << c.frames << ": " << what << "\n    fast: '" << ta.event << "', box "
          << box(ta.tracked_box_px) << "\n    reference: '" << tb.event << "', box " << box(tb.tracked_box_px) << "\n";
    }
    c.same = false;
  };
  for (;;) {
    const Frame* f = fast.next();
    const Frame* g = reference.next();
    if (!f || !g) {
      if (f || g) fail("one sequence ended before the other");
      break;
    }
    if (f != g) fail("different frames fed (" + f->spec.name + " vs " + g->spec.name + ")");
    fast.driver().step_frame();
    reference.driver().step_frame();
    const flight_sw::FlightSoftware& a = fast.driver().fsw();
    const flight_sw::FlightSoftware& b = reference.driver().fsw();
    const flight_sw::Telemetry& ta = a.telemetry();
    const flight_sw::Telemetry& tb = b.telemetry();
    if (a.phase() != b.phase()) fail(std::string("phase ") + phase_name(a.phase()) + " vs " + phase_name(b.phase()));
    if (!(ta.target == tb.target)) fail("target " + cell(ta.target) + " vs " + cell(tb.target));
    if (ta.full_view != tb.full_view) fail("full view differs");
    if (a.inventory_json() != b.inventory_json()) fail("inventory so far differs");
    if (!(ta.rc == tb.rc)) fail("commands differ (" + ta.rc.text() + " vs " + tb.rc.text() + ")");
    const auto& va = ta.velocity;
    const auto& vb = tb.velocity;
    const double dv = std::max({std::abs(va.vx_B_mps - vb.vx_B_mps), std::abs(va.vy_B_mps - vb.vy_B_mps),
                                std::abs(va.vz_mps - vb.vz_mps), std::abs(va.yaw_rate_radps - vb.yaw_rate_radps)});
    if (dv > kVelocityTolerance) fail("velocity commands differ by " + std::to_string(dv));
    if (ta.pose.has_value() != tb.pose.has_value()) fail("one has a pose, the other not");
    if (ta.pose && tb.pose) {
      ++c.poses_compared;
      const double dp = (ta.pose->p_FB_m() - tb.pose->p_FB_m()).norm();
      const double dr = std::abs(std::remainder(ta.pose->yaw_rad - tb.pose->yaw_rad, 2.0 * M_PI));
      c.max_pose_diff_m = std::max(c.max_pose_diff_m, dp);
      c.max_pose_diff_rad = std::max(c.max_pose_diff_rad, dr);
      if (dp > kPoseTolerance_m || dr > kPoseTolerance_rad) fail("pose differs by " + std::to_string(dp) + " m");
    }
    if (!last_phase || *last_phase != a.phase()) {
      c.phases += std::string(c.phases.empty() ? "" : " ") + phase_name(a.phase()) + "@" + std::to_string(c.frames);
      last_phase = a.phase();
    }
    ++c.frames;
  }
  const flight_sw::FlightSoftware& a = fast.driver().fsw();
  const flight_sw::FlightSoftware& b = reference.driver().fsw();
  c.target = cell(a.telemetry().target);
  c.inventory = a.inventory_json();
  if (a.inventory_json() != b.inventory_json()) fail("inventories differ:\n" + a.inventory_json() + "\n" + b.inventory_json());
  std::ostringstream os;
  os << condition << ": " << c.frames << " frames; phases " << c.phases << "; target " << c.target << "; "
     << c.poses_compared << " poses, largest difference " << c.max_pose_diff_m << " m, " << c.max_pose_diff_rad
     << " rad; " << (c.same ? "same decisions" : "DIFFERENT decisions") << "\n"
     << why.str();
  c.summary = os.str();
  return c;
}

}  // namespace shelfcross::bench
