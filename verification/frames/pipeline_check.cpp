#include "verification/frames/pipeline_check.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "flight_sw/text.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::frames {

PipelineComparison compare_pipelines(const FrameSet& set, const std::string& condition,
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
  const auto cell = [](const std::optional<CellIndex>& t) { return t ? flight_sw::cell_text(*t) : std::string("none"); };
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
          << box(ta.tracking.tracked_box_px) << "\n    reference: '" << tb.event << "', box " << box(tb.tracking.tracked_box_px) << "\n";
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
    if (!(ta.tracking.target == tb.tracking.target)) fail("target " + cell(ta.tracking.target) + " vs " + cell(tb.tracking.target));
    if (ta.view.full_view != tb.view.full_view) fail("full view differs");
    if (a.inventory_json() != b.inventory_json()) fail("inventory so far differs");
    if (!(ta.control.rc == tb.control.rc)) fail("commands differ (" + ta.control.rc.text() + " vs " + tb.control.rc.text() + ")");
    const auto& va = ta.control.velocity;
    const auto& vb = tb.control.velocity;
    const double dv = std::max({std::abs(va.vx_B_mps - vb.vx_B_mps), std::abs(va.vy_B_mps - vb.vy_B_mps),
                                std::abs(va.vz_mps - vb.vz_mps), std::abs(va.yaw_rate_radps - vb.yaw_rate_radps)});
    if (dv > kVelocityTolerance) fail("velocity commands differ by " + std::to_string(dv));
    if (ta.pose.has_value() != tb.pose.has_value()) fail("one has a pose, the other not");
    if (ta.pose && tb.pose) {
      ++c.poses_compared;
      const double dp = (ta.pose->p_FB_m() - tb.pose->p_FB_m()).norm();
      const double dr = std::abs(wrap_pi(ta.pose->yaw_rad - tb.pose->yaw_rad));
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
  c.target = cell(a.telemetry().tracking.target);
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

TagComparison compare_tag_detection(const FrameSet& set, flight_sw::FlightConfig config) {
  const double threshold = config.perception.area_ratio_threshold;
  config.perception.pipeline = flight_sw::PerceptionPipeline::fast;
  flight_sw::TagDetector fast(config.perception);
  config.perception.pipeline = flight_sw::PerceptionPipeline::reference;
  flight_sw::TagDetector reference(config.perception);
  TagComparison c;
  std::string first;
  std::vector<flight_sw::TagBlob> a, b;
  for (const Frame& f : set.frames) {
    a.clear();
    b.clear();
    const cv::Rect whole(0, 0, f.bgr.cols, f.bgr.rows);
    fast.detect(f.bgr, whole, a);
    reference.detect(f.bgr, whole, b);
    c.raw_missed += static_cast<int>(b.size()) - static_cast<int>(a.size());
    flight_sw::keep_front_shelf(a, threshold);
    flight_sw::keep_front_shelf(b, threshold);
    bool same = a.size() == b.size();
    for (size_t i = 0; same && i < a.size(); ++i) {
      same = a[i].centre_px == b[i].centre_px && a[i].area_px == b[i].area_px && a[i].bbox_px == b[i].bbox_px;
    }
    if (!same && first.empty()) {
      first = f.spec.name + " (" + std::to_string(a.size()) + " vs " + std::to_string(b.size()) + " front tags)";
    }
    c.same = c.same && same;
    ++c.frames;
    c.front_tags += static_cast<int>(b.size());
  }
  c.summary = "whole-frame tags after eq. 1: " + std::to_string(c.frames) + " frames, " + std::to_string(c.front_tags) +
              " front tags: " + (c.same ? "identical" : "DIFFERENT, first at " + first) + " (before eq. 1 the fast " +
              "detector skipped " + std::to_string(c.raw_missed) + " slivers eq. 1 drops)\n";
  return c;
}

}  // namespace shelfcross::frames
