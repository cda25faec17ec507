#pragma once
// Test helper for the mission's tests: a kinematic vehicle flown by the flight software's
// commands, seeing drawn frames of the mission's scene (mission_scene.hpp), and what the tests
// check of a run seen from outside (where it crossed, where it landed).
//
// The test vehicle is kinematic: rc sticks are velocities through the configured gains
// (exactly what the flight software assumes), takeoff puts it at 1 m. It is a harness for
// driving the entry point with consistent stamped inputs, not a model of the Tello.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flight_sw/mission/flight_software.hpp"
#include "flight_sw/mission/test/mission_scene.hpp"

namespace shelfcross::flight_sw::testing {

struct Options {
  std::int64_t frame_rate_hz = 15;
  std::function<bool(TimeNs)> frames_on = [](TimeNs) { return true; };
  std::function<int(TimeNs)> battery = [](TimeNs) { return 90; };
  std::vector<std::string> takeoff_replies = {"ok"};  ///< per attempt; "" = no reply
  /// The first `takeoff` arrives twice (a duplicated datagram): the drone takes the first copy
  /// (motors idle 1 s, then up at 0.45 m/s to 1 m) and refuses the second at once with
  /// "error", the reply the flight software hears; every later `takeoff` is refused too. (The
  /// first copy's "ok", once up, is left out: it would be drained as stale.)
  bool takeoff_duplicated = false;
  /// Per attempt of `land`: the drone lands on the first, and replies this ("" = the reply is
  /// lost); later attempts find it on the ground and get "error", as from a Tello.
  std::string land_reply = "ok";
  /// The first `land` arrives twice (a duplicated datagram): the drone starts landing on the
  /// first, refuses the duplicate at once with "error", and that is the reply the flight
  /// software hears; the first's "ok", once down, comes after it and is drained as stale.
  bool land_duplicated = false;
  Eigen::Vector3d start_W_m = Eigen::Vector3d(0.3, 0.0, 0.0);
  double start_yaw_rad = 0.0;
  bool blank_frames = false;  ///< frames show only the wall
  double blank_after_approach_s = -1.0;  ///< >= 0: frames go blank this long into the approach
  /// >= 0: from this long into the approach every picture is damaged throughout, with more lost
  /// bands than steer_max_damage_events (a link too lossy to fly on): it neither decides nor steers.
  double ruin_after_approach_s = -1.0;
  /// > 0: after the first re-read (FindShelf again, after an approach) the frames show only
  /// the wall this long: from close, the inside of a cell and no tag.
  double blank_after_reread_s = -1.0;
  double video_latency_s = 0.0;          ///< a frame reaches the flight software this late
  double velocity_time_constant_s = 0.0;  ///< > 0: horizontal velocity lags the sticks (first order)
  double yaw_time_constant_s = 0.0;       ///< > 0: yaw rate lags the stick (first order)
  double vertical_time_constant_s = 0.0;  ///< > 0: vertical speed lags the stick (first order)
  /// A vertical speed nobody commanded, added in the crossing (m/s, up positive): a slow sink
  /// the open-loop crossing cannot see (run 19 of grid_2x2 seed 2 sank 21 cm in its crossing).
  double crossing_sink_mps = 0.0;
  /// A headwind met in the crossing (m/s, along the heading, slowing the vehicle over the
  /// ground): the open-loop crossing cannot see it; the state's velocities (the Tello's
  /// downward optical flow measures ground speed) do.
  double crossing_headwind_mps = 0.0;
  /// A horizontal velocity over the ground nobody commanded (world frame, m/s) by time and
  /// phase: a gust's push, a drift. The state's velocities (ground speed) show it.
  std::function<Eigen::Vector2d(double, Phase)> push_W_mps = [](double, Phase) { return Eigen::Vector2d::Zero(); };
  /// > 0: error-concealed video in groups of pictures of this many frames: frames k of a group
  /// (k = 0 the key frame) are whole up to damage_first_frame, then one more band is lost in
  /// each (damage_events = k - damage_first_frame + 1), and the lower half of a damaged frame
  /// is guessed: it shows the picture damage_shift_px rows lower (stale content, every tag and
  /// marker there drawn too high).
  int damage_group_frames = 0;
  int damage_first_frame = 1;
  int damage_shift_px = 0;
  /// > 0: the guessed part begins at this row instead of half way down.
  int damage_top_px = 0;
  /// The receiver placed the damage: CameraFrame::damaged_rows is the guessed part.
  bool damage_rows_known = false;
  /// >= 0: this long into the approach the video goes blank for slide_blank_s, and meanwhile
  /// the vehicle is moved by slide_W_m (a gust, a drift the flight software never saw): the
  /// target's box, re-acquired where it was in the picture, then sits on another cell.
  double slide_after_approach_s = -1.0;
  double slide_blank_s = 1.0;
  Eigen::Vector3d slide_W_m = Eigen::Vector3d::Zero();
  /// False: the state height misses the slide's climb (its time-of-flight sensor over a
  /// raised floor reads the old height), so the state odometry does not see it either.
  bool slide_seen_by_height = true;
  /// Added to the position once, at the first picture of TakeInventory: the viewpoint was
  /// reached still moving and the hover coasted on (over the tops, a transfer's descent at
  /// 0.3 m/s sank 0.13 m on and took the grid's top row out of the view).
  Eigen::Vector3d coast_at_inventory_W_m = Eigen::Vector3d::Zero();
};

/// The damage of one frame handed over and what the flight software did on it.
struct FrameStep {
  TimeNs t_ns = 0;
  int damage_events = 0;
  Phase before = Phase::Idle, after = Phase::Idle;
  std::vector<std::string> rc;  ///< rc commands sent on it
};

class Harness {
 public:
  explicit Harness(Options o = {}, FlightConfig config = {})
      : o_(std::move(o)), fsw_(config), config_(config), scene_(mission_scene()), drawer_(config.camera, true) {
    p_WB_ = o_.start_W_m;
    yaw_ = o_.start_yaw_rad;
  }

  /// Runs until the flight software finishes, t_end_s, or `until` holds (checked after each
  /// input: a test that needs a flight only up to an event stops there).
  void run(double t_end_s, const std::function<bool(const Harness&)>& until = {}) {
    handle(fsw_.start(0));
    const TimeNs end = seconds_to_ns(t_end_s);
    std::int64_t frame_k = 1, state_k = 1;
    while (!fsw_.finished() && t_ < end && !(until && until(*this))) {
      const TimeNs t_frame = tick_time_ns(frame_k, o_.frame_rate_hz);
      const TimeNs t_state = tick_time_ns(state_k, 10);
      const TimeNs t_reply = replies_.empty() ? end : replies_.front().t_ns;
      const TimeNs t_video = in_flight_.empty() ? end : in_flight_.front().t_ns;
      const TimeNs t_next = std::min({t_frame, t_state, t_reply, t_video, end});
      advance(t_next);
      if (t_next == t_video && !in_flight_.empty()) {
        CameraFrame f = in_flight_.front();
        in_flight_.pop_front();
        step_frame(f);
      } else if (t_next == t_reply && !replies_.empty()) {
        const SdkReply r = replies_.front();
        replies_.pop_front();
        handle(fsw_.step(r));
      } else if (t_next == t_state) {
        ++state_k;
        StateRecord s;
        s.t_ns = t_;
        s.yaw_rad = yaw_;
        s.height_m = p_WB_.z() + height_bias_m_;
        // Velocities in the heading frame at the SDK's resolution (vgx, vgy: 0.1 m/s).
        const Eigen::Vector2d v_ground_H = ground_velocity_H();
        s.vx_H_mps = std::round(v_ground_H.x() * 10.0) / 10.0;
        s.vy_H_mps = std::round(v_ground_H.y() * 10.0) / 10.0;
        s.vz_H_mps = std::round(vz_ * 10.0) / 10.0;
        s.battery_pct = o_.battery(t_);
        handle(fsw_.step(s));
      } else if (t_next == t_frame) {
        ++frame_k;
        if (fsw_.phase() == Phase::Approach && !approach_t_) approach_t_ = t_;
        if (fsw_.phase() == Phase::TakeInventory && !coasted_) {
          p_WB_ += o_.coast_at_inventory_W_m;
          coasted_ = true;
        }
        if (fsw_.phase() == Phase::FindShelf && approach_t_ && !reread_t_) {
          reread_t_ = t_;
          reread_W_m_ = p_WB_;
        }
        bool blank = o_.blank_frames || (o_.blank_after_approach_s >= 0.0 && approach_t_ &&
                                         t_ - *approach_t_ > seconds_to_ns(o_.blank_after_approach_s));
        if (o_.blank_after_reread_s > 0.0 && reread_t_ && t_ - *reread_t_ <= seconds_to_ns(o_.blank_after_reread_s)) {
          blank = true;
          reread_end_W_m_ = p_WB_;
          reread_end_yaw_rad_ = yaw_;
        }
        if (o_.slide_after_approach_s >= 0.0 && approach_t_ && t_ - *approach_t_ > seconds_to_ns(o_.slide_after_approach_s)) {
          const bool in_gap = t_ - *approach_t_ <= seconds_to_ns(o_.slide_after_approach_s + o_.slide_blank_s);
          blank = blank || in_gap;
          if (!slid_) {
            p_WB_ += o_.slide_W_m;
            if (!o_.slide_seen_by_height) height_bias_m_ = -o_.slide_W_m.z();
            slid_ = true;
          }
        }
        if (video_on_ && o_.frames_on(t_)) {
          CameraFrame f;
          f.t_ns = t_;
          f.index = frame_k;
          f.bgr = picture(blank);
          if (o_.video_latency_s > 0.0) {  // taken now, handed over later
            f.t_ns = t_ + seconds_to_ns(o_.video_latency_s);
            in_flight_.push_back(std::move(f));
            continue;
          }
          if (o_.damage_group_frames > 0) damage(f);
          if (o_.ruin_after_approach_s >= 0.0 && approach_t_ && t_ - *approach_t_ > seconds_to_ns(o_.ruin_after_approach_s)) {
            f.damaged = true;
            f.damage_events = config_.perception.steer_max_damage_events + 1;
            f.damaged_rows = {{0, f.bgr.rows}};
            if (!ruin_W_m_) ruin_W_m_ = p_WB_;
          }
          step_frame(f);
        }
      }
    }
  }

  FlightSoftware& fsw() { return fsw_; }
  bool slid() const { return slid_; }
  const std::vector<SdkCommand>& commands() const { return log_; }
  /// When each command `text` was sent, in order.
  std::vector<TimeNs> sent(const std::string& text) const {
    std::vector<TimeNs> t;
    for (const SdkCommand& c : log_) {
      if (c.text == text) t.push_back(c.t_ns);
    }
    return t;
  }
  std::vector<std::string> non_rc() const {
    std::vector<std::string> v;
    for (const auto& c : log_) {
      if (c.text.rfind("rc ", 0) != 0) v.push_back(c.text);
    }
    return v;
  }
  /// Where the first re-read started, and the pose at the last blank frame after it.
  const Eigen::Vector3d& reread_W_m() const { return reread_W_m_; }
  const Eigen::Vector3d& reread_end_W_m() const { return reread_end_W_m_; }
  /// Where the vehicle was at the first ruined picture (Options::ruin_after_approach_s).
  const std::optional<Eigen::Vector3d>& ruin_W_m() const { return ruin_W_m_; }
  double reread_end_yaw_rad() const { return reread_end_yaw_rad_; }
  bool saw_phase(Phase p) const { return std::find(phases_.begin(), phases_.end(), p) != phases_.end(); }
  const std::vector<Eigen::Vector4d>& track() const { return track_; }  // t, x, y, z
  /// The heading (rad) at each step of track().
  const std::vector<double>& yaw_track() const { return yaw_track_; }
  const Eigen::Vector3d& position() const { return p_WB_; }
  TimeNs now() const { return t_; }
  const std::vector<FrameStep>& frame_steps() const { return frame_steps_; }

 private:
  void step_frame(const CameraFrame& f) {
    FrameStep st;
    st.t_ns = t_;
    st.damage_events = f.damage_events;
    st.before = fsw_.phase();
    phases_.push_back(st.before);
    const std::vector<SdkCommand> cmds = fsw_.step(f);
    for (const SdkCommand& c : cmds) {
      if (c.text.rfind("rc ", 0) == 0) st.rc.push_back(c.text);
    }
    handle(cmds);
    st.after = fsw_.phase();
    phases_.push_back(st.after);
    frame_steps_.push_back(std::move(st));
  }

  // What the camera sees now, in a buffer no frame handed over still holds (the flight
  // software may keep a picture): a bare wall when blank, else the scene from the vehicle's
  // pose. Drawing is a function of the pose alone (the scene and the mount are fixed), so a
  // pose unchanged since the last drawing (a hover: the kinematic vehicle stands exactly
  // still) gives the same picture without drawing it again.
  cv::Mat picture(bool blank) {
    auto free = std::find_if(pictures_.begin(), pictures_.end(), [](const cv::Mat& m) { return m.u->refcount == 1; });
    if (free == pictures_.end()) {
      pictures_.emplace_back(config_.camera.height_px, config_.camera.width_px, CV_8UC3);
      free = std::prev(pictures_.end());
    }
    if (blank) {
      *free = cv::Scalar(185, 185, 180);
      return *free;
    }
    const Eigen::Vector4d pose(p_WB_.x(), p_WB_.y(), p_WB_.z(), yaw_);
    if (!drawn_pose_ || *drawn_pose_ != pose) {
      drawer_.draw(scene_, camera_pose_W(p_WB_, yaw_, 0, 0, config_.mount), drawn_);
      drawn_pose_ = pose;
    }
    drawn_.copyTo(*free);
    return *free;
  }

  // Concealment as the receiver hands it over (see Options::damage_group_frames).
  void damage(CameraFrame& f) const {
    const int k = static_cast<int>(f.index % o_.damage_group_frames);
    if (k < o_.damage_first_frame) return;
    f.damaged = true;
    f.damage_events = k - o_.damage_first_frame + 1;
    const int h = f.bgr.rows, top = o_.damage_top_px > 0 ? o_.damage_top_px : h / 2, shift = o_.damage_shift_px;
    cv::Mat guessed(h - top, f.bgr.cols, f.bgr.type(), cv::Scalar(185, 185, 180));
    f.bgr.rowRange(top + shift, h).copyTo(guessed.rowRange(0, h - top - shift));
    guessed.copyTo(f.bgr.rowRange(top, h));
    f.damaged_rows = o_.damage_rows_known ? std::vector<RowSpan>{{top, h}} : std::vector<RowSpan>{{0, h}};
  }

  void handle(const std::vector<SdkCommand>& cmds) {
    for (const SdkCommand& c : cmds) {
      EXPECT_EQ(c.t_ns, t_);
      log_.push_back(c);
      if (c.text.rfind("rc ", 0) == 0) {
        EXPECT_TRUE(airborne_) << "rc while on the ground";
        std::istringstream in(c.text.substr(3));
        in >> rc_.a >> rc_.b >> rc_.c >> rc_.d;
        for (int v : {rc_.a, rc_.b, rc_.c, rc_.d}) EXPECT_LE(std::abs(v), 100);
        continue;
      }
      EXPECT_TRUE(replies_.empty()) << "'" << c.text << "' sent while a reply is outstanding";
      if (c.text == "command") {
        replies_.push_back({t_ + 20 * kMs, "ok"});
      } else if (c.text == "streamon") {
        replies_.push_back({t_ + 20 * kMs, "ok"});
        video_on_ = true;
      } else if (c.text == "takeoff" && o_.takeoff_duplicated) {
        if (!climb_from_ns_) climb_from_ns_ = t_ + 1000 * kMs;
        replies_.push_back({t_ + 30 * kMs, "error"});
      } else if (c.text == "takeoff") {
        const size_t k = std::min(takeoff_attempt_++, o_.takeoff_replies.size() - 1);
        const std::string& reply = o_.takeoff_replies[k];
        if (reply == "ok") {
          airborne_ = true;
          p_WB_.z() = 1.0;
        }
        if (!reply.empty()) replies_.push_back({t_ + 1500 * kMs, reply});
      } else if (c.text == "land") {
        // A Tello refuses `land` at once while landing or landed; it answers one that starts
        // a landing once down.
        if (landing_ || o_.land_duplicated) {
          replies_.push_back({t_ + 30 * kMs, "error"});
        } else if (!o_.land_reply.empty()) {
          replies_.push_back({t_ + 1000 * kMs, o_.land_reply});
        }
        landing_ = true;
      }
    }
  }

  /// Over the ground, in the heading frame: the autopilot's velocity less a crossing headwind.
  Eigen::Vector2d ground_velocity_H() const {
    const double headwind = fsw_.phase() == Phase::Cross ? o_.crossing_headwind_mps : 0.0;
    const Eigen::Vector2d push_W = airborne_ && !landing_ ? o_.push_W_mps(ns_to_seconds(t_), fsw_.phase())
                                                          : Eigen::Vector2d::Zero();
    const double c = std::cos(yaw_), s = std::sin(yaw_);
    return v_H_ - Eigen::Vector2d(headwind, 0.0) + Eigen::Vector2d(c * push_W.x() + s * push_W.y(), -s * push_W.x() + c * push_W.y());
  }

  // Kinematics: rc through the configured gains, in the heading frame.
  void advance(TimeNs t_next) {
    while (t_ < t_next) {
      const TimeNs dt_ns = std::min<TimeNs>(5 * kMs, t_next - t_);
      const double dt = ns_to_seconds(dt_ns);
      if (landing_) {  // down at 1 m/s
        p_WB_.z() = std::max(0.0, p_WB_.z() - 1.0 * dt);
        vz_ = p_WB_.z() > 0.0 ? -1.0 : 0.0;
      }
      if (climb_from_ns_ && !airborne_ && t_ >= *climb_from_ns_) {  // Options::takeoff_duplicated
        p_WB_.z() = std::min(1.0, p_WB_.z() + 0.45 * dt);
        vz_ = p_WB_.z() < 1.0 ? 0.45 : 0.0;
        airborne_ = p_WB_.z() >= 1.0;
      }
      if (airborne_ && !landing_) {
        const Eigen::Vector2d v_cmd(rc_.b / config_.rc.rc_per_mps_horizontal,
                                    -rc_.a / config_.rc.rc_per_mps_horizontal);
        const double tau = o_.velocity_time_constant_s;
        v_H_ = tau > 0.0 ? Eigen::Vector2d(v_H_ + (v_cmd - v_H_) * std::min(1.0, dt / tau)) : v_cmd;
        const double vx = ground_velocity_H().x(), vy = ground_velocity_H().y();
        p_WB_.x() += (std::cos(yaw_) * vx - std::sin(yaw_) * vy) * dt;
        p_WB_.y() += (std::sin(yaw_) * vx + std::cos(yaw_) * vy) * dt;
        const double vz_cmd = rc_.c / config_.rc.rc_per_mps_vertical;
        const double tau_z = o_.vertical_time_constant_s;
        vz_ = tau_z > 0.0 ? vz_ + (vz_cmd - vz_) * std::min(1.0, dt / tau_z) : vz_cmd;
        const double sink = fsw_.phase() == Phase::Cross ? o_.crossing_sink_mps : 0.0;
        p_WB_.z() += (vz_ + sink) * dt;
        const double w_cmd = -rc_.d / config_.rc.rc_per_radps_yaw;
        const double tau_w = o_.yaw_time_constant_s;
        w_ = tau_w > 0.0 ? w_ + (w_cmd - w_) * std::min(1.0, dt / tau_w) : w_cmd;
        yaw_ += w_ * dt;
      }
      t_ += dt_ns;
      track_.push_back({ns_to_seconds(t_), p_WB_.x(), p_WB_.y(), p_WB_.z()});
      yaw_track_.push_back(yaw_);
    }
  }

  Options o_;
  FlightSoftware fsw_;
  FlightConfig config_;
  Scene scene_;
  Drawer drawer_;
  cv::Mat drawn_;                             ///< the last picture drawn
  std::optional<Eigen::Vector4d> drawn_pose_;  ///< from where (x, y, z, yaw)
  std::deque<cv::Mat> pictures_;              ///< buffers of the pictures handed over
  TimeNs t_ = 0;
  std::optional<TimeNs> approach_t_;
  std::optional<TimeNs> reread_t_;  ///< the first frame of the first re-read
  Eigen::Vector3d reread_W_m_ = Eigen::Vector3d::Zero(), reread_end_W_m_ = Eigen::Vector3d::Zero();
  double reread_end_yaw_rad_ = 0.0;
  std::optional<Eigen::Vector3d> ruin_W_m_;
  bool slid_ = false;
  bool coasted_ = false;
  double height_bias_m_ = 0.0;  ///< the state height's error (slide_seen_by_height)
  Eigen::Vector3d p_WB_;
  double yaw_ = 0.0;
  bool video_on_ = false, airborne_ = false, landing_ = false;
  size_t takeoff_attempt_ = 0;
  std::optional<TimeNs> climb_from_ns_;  ///< Options::takeoff_duplicated: the climb starts
  RcSticks rc_;
  std::deque<SdkReply> replies_;
  std::deque<CameraFrame> in_flight_;  ///< frames taken, not yet handed over
  Eigen::Vector2d v_H_ = Eigen::Vector2d::Zero();  ///< horizontal velocity, heading frame
  double w_ = 0.0;                                 ///< yaw rate
  double vz_ = 0.0;                                ///< vertical speed commanded (lagged)
  std::vector<SdkCommand> log_;
  std::vector<Phase> phases_;
  std::vector<FrameStep> frame_steps_;
  std::vector<Eigen::Vector4d> track_;
  std::vector<double> yaw_track_;
};

// A give-up as seen from outside: a straight back-off (rc 0 -20 0 0, back_off_speed_mps) and a
// landing within 10 cm of give_up_clearance_m in front of the shelf's face (x 3 m).
inline void expect_backed_out_and_landed_clear(const Harness& h, const FlightConfig& c) {
  bool backed_off = false;
  for (const auto& cmd : h.commands()) backed_off = backed_off || cmd.text == "rc 0 -20 0 0";
  EXPECT_TRUE(backed_off);
  EXPECT_LT(h.position().x(), 3.0 - c.mission.line_hold.give_up_clearance_m + 0.1) << "landed clear of the shelf";
}

/// When the frame steps first enter `phase` (s since the start), if they do.
inline std::optional<double> first_entry_s(const Harness& h, Phase phase) {
  for (const FrameStep& st : h.frame_steps()) {
    if (st.before != phase && st.after == phase) return ns_to_seconds(st.t_ns);
  }
  return std::nullopt;
}

/// Through the opening of cell (2, 3) of the front shelf: y between posts 2 and 3 (0 and
/// -0.34 m), z between beams 1 and 2 (0.64 and 0.98 m), less the posts, beams and the vehicle's
/// half size at every sample inside the shelf's depth; and, when given, the entry within
/// entry_tol_m (y, z) of the cell centre (-0.17, 0.81) m.
inline void expect_through_cell_2_3(const Harness& h, std::optional<Eigen::Vector2d> entry_tol_m = std::nullopt) {
  bool entered = false;
  for (const auto& s : h.track()) {
    if (s[1] < 3.0 || s[1] > 3.34) continue;
    if (!entered && entry_tol_m) {
      EXPECT_NEAR(s[2], -0.17, entry_tol_m->x()) << "entry, t " << s[0];
      EXPECT_NEAR(s[3], 0.81, entry_tol_m->y()) << "entry, t " << s[0];
    }
    entered = true;
    EXPECT_GT(s[2], -0.33 + 0.0925 / 2) << "t " << s[0];
    EXPECT_LT(s[2], -0.01 - 0.0925 / 2) << "t " << s[0];
    EXPECT_GT(s[3], 0.65 + 0.041 / 2) << "t " << s[0];
    EXPECT_LT(s[3], 0.97 - 0.041 / 2) << "t " << s[0];
  }
  EXPECT_TRUE(entered) << "never reached the shelf";
}

// When the track lands: the position at the `land` command.
inline std::optional<Eigen::Vector3d> position_at_land(const Harness& h) {
  const auto& cmds = h.commands();
  const auto land = std::find_if(cmds.begin(), cmds.end(), [](const SdkCommand& c) { return c.text == "land"; });
  if (land == cmds.end()) return std::nullopt;
  for (const auto& s : h.track()) {
    if (s[0] >= ns_to_seconds(land->t_ns)) return Eigen::Vector3d(s[1], s[2], s[3]);
  }
  return std::nullopt;
}

}  // namespace shelfcross::flight_sw::testing
