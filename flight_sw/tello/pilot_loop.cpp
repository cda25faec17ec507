#include "flight_sw/tello/pilot_loop.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <variant>

#include <opencv2/imgcodecs.hpp>

namespace shelfcross::tello {
namespace {

enum Tag : int { kTagFlightSoftware = 1, kTagPilot = 2 };

const char* origin_name(int tag) {
  switch (tag) {
    case kTagFlightSoftware: return "fsw";
    case kTagPilot: return "pilot";
    default: return "driver";
  }
}

// Picture rows a frame's damage may cover (the log's measure of how much is guesswork).
int damaged_row_count(const VideoFrame& f) {
  int rows = 0;
  for (const RowSpan& r : f.damaged_rows) rows += r.v_end_px - r.v_begin_px;
  return rows;
}

DriverConfig driver_config(const PilotLoopConfig& c) {
  DriverConfig dc = c.driver;
  // Keep a stick setpoint alive at least as long as the flight software may go without
  // renewing it (its keep-alive), plus margin.
  dc.rc_hold_ns = std::max(dc.rc_hold_ns, seconds_to_ns(c.flight.rc.keepalive_s + 0.5));
  dc.command_gap_ns = std::max(dc.command_gap_ns, seconds_to_ns(c.flight.timeouts.command_gap_s));
  return dc;
}

}  // namespace

class PilotLoop::Impl {
 public:
  Impl(const PilotLoopConfig& o, const Clock& clock, PilotChannels channels)
      : o_(o), clock_(clock), log_(o.log_path), fsw_(o.flight) {
    if (channels.command || channels.state) {
      driver_ = std::make_unique<SdkDriver>(driver_config(o_), clock_, std::move(channels.command),
                                            std::move(channels.state));
    } else {
      driver_ = std::make_unique<SdkDriver>(driver_config(o_), clock_);
    }
    video_ = channels.video ? std::make_unique<VideoReceiver>(o_.video, clock_, std::move(channels.video))
                            : std::make_unique<VideoReceiver>(o_.video, clock_);
  }

  void start() {
    if (!o_.record_dir.empty()) std::filesystem::create_directories(o_.record_dir);
    start_ns_ = clock_.now_ns();
    last_tick_ns_ = start_ns_;
    log_.write(start_ns_, "start",
               {{"drone", o_.driver.drone_ip + ":" + std::to_string(o_.driver.drone_command_port)},
                {"local_command_port", driver_->local_command_port()},
                {"state_port", driver_->local_state_port()},
                {"video_port", video_->local_port()},
                {"dry_run", o_.driver.dry_run},
                {"mode", o_.mode},
                {"flight_config", o_.flight_config_path},
                {"calibration", o_.calibration_path}});
    submit_fsw(fsw_.start(start_ns_));
  }

  std::optional<int> step(int signals) {
    video_->service();
    driver_->service();
    step_flight_software();
    if (auto exit_code = supervise(signals)) return exit_code;
    driver_->service();
    return std::nullopt;
  }

  // Driver events -> log and flight-software inputs; the newest frame likewise.
  void step_flight_software() {
    std::vector<flight_sw::Input> inputs;
    for (DriverEvent& e : driver_->take_events()) {
      log_event(e);
      using K = DriverEvent::Kind;
      if (e.kind == K::State && e.state) {
        last_state_ns_ = e.t_ns;
        battery_pct_ = e.state->battery_pct;
        last_height_m_ = e.state->height_m;
        inputs.emplace_back(*e.state);
      } else if (e.kind == K::Sent && e.command == "takeoff") {
        if (!airborne_) airborne_since_ns_ = e.t_ns;
        airborne_ = true;
      } else if (e.kind == K::Reply || e.kind == K::Failed) {
        const bool ok = e.kind == K::Reply && flight_sw::is_ok_reply(e.reply);
        // A `land` whose `ok` was lost: repeated, it finds the drone on the ground and gets
        // `error`, or times out; the state height says whether it is down.
        if (e.command == "land" && (ok || grounded())) airborne_ = false;
        // A refused takeoff ("error No valid imu", ...) left the drone on the ground, unless
        // the state stream says otherwise.
        if (e.command == "takeoff" && e.kind == K::Reply && !ok &&
            !(last_height_m_ && *last_height_m_ > airborne_height_m())) {
          airborne_ = false;
        }
        if (e.tag == kTagFlightSoftware && e.kind == K::Reply) inputs.emplace_back(SdkReply{e.t_ns, e.reply});
        if (e.tag == kTagPilot && e.command == "land") {
          land_done_ = true;
          land_ok_ = ok || grounded();
        }
      }
    }
    std::optional<VideoFrame> f = video_->take_latest();
    if (f) {
      const TimeNs taken = clock_.now_ns();
      log_.write(taken, "frame", {{"index", f->index}, {"rx_ns", f->t_ns}, {"handed_ns", f->handed_ns},
                                  {"damaged", f->damaged}, {"key_group", f->key_group},
                                  {"damage_events", f->damage_events}, {"damaged_rows", damaged_row_count(*f)},
                                  {"rows", f->bgr.rows}, {"cols", f->bgr.cols}});
      last_frame_ns_ = f->handed_ns;
      if (!o_.record_dir.empty()) record(*f);
      if (hover_override_) {
        hover_override_ = false;
        log_.write(taken, "failsafe", {{"event", "video back: control returned to the flight software"}});
      }
      // Damaged (error-concealed) pictures go through, marked: the flight software knows
      // how far to trust them (perception.decide_/steer_max_damage_events).
      inputs.emplace_back(CameraFrame{f->handed_ns, f->index, std::move(f->bgr), f->damaged, f->damage_events,
                                      std::move(f->damaged_rows)});
    }
    // The flight computer's timer: with nothing else to hand over, a tick every 50 ms lets
    // the flight software's timeouts and retries fire (a lost first "command" is resent).
    if (inputs.empty()) {
      const TimeNs now = clock_.now_ns();
      if (now - last_tick_ns_ >= kTickPeriodNs) {
        last_tick_ns_ = now;
        inputs.emplace_back(flight_sw::ClockTick{now});
      }
    }
    auto stamp = [](const flight_sw::Input& in) { return std::visit([](const auto& m) { return m.t_ns; }, in); };
    std::stable_sort(inputs.begin(), inputs.end(),
                     [&](const auto& a, const auto& b) { return stamp(a) < stamp(b); });
    for (auto& in : inputs) {
      if (fsw_.finished()) break;
      // Stamps never go backwards (a frame decoded on the receiver thread may be stamped
      // just before a state record read earlier in this loop).
      std::visit([&](auto& m) { m.t_ns = std::max(m.t_ns, last_fed_ns_); }, in);
      last_fed_ns_ = stamp(in);
      submit_fsw(fsw_.step(in));
      log_telemetry();
      start_stick_program();
      if (const auto* frame = std::get_if<CameraFrame>(&in)) {
        log_approach_view();
        if (o_.on_frame) o_.on_frame(*frame, fsw_);
      }
    }
  }

  // The stick program starts when the flight software has the drone airborne (FindShelf:
  // its takeoff acknowledged, or the height saying so when the reply was lost).
  void start_stick_program() {
    if (!o_.stick_program || program_start_ns_ || program_done_ || fsw_.phase() != flight_sw::Phase::FindShelf) return;
    program_start_ns_ = clock_.now_ns();
    log_.write(*program_start_ns_, "stick_program", {{"event", "started"}, {"mode", o_.mode}});
    if (o_.console) *o_.console << "tello_pilot: " << o_.mode << " started" << std::endl;
  }

  // One pass of the stick program while airborne; true when it ended the flight (landing).
  bool fly_stick_program(TimeNs now) {
    if (!program_start_ns_) return false;
    const flight_sw::Phase phase = fsw_.phase();
    if (phase == flight_sw::Phase::Land || phase == flight_sw::Phase::Done) {
      // The flight software's own failsafe is landing the drone: the program stops.
      stop_stick_program(now, "stopped: the flight software lands (" + fsw_.telemetry().event + ")");
      return false;
    }
    if (!fsw_.telemetry().tags.empty()) {
      stop_stick_program(now, "stopped: shelf tags in view");
      begin_land(o_.mode + " stopped: shelf tags in view (an obstacle near: fly it in open space)", 1);
      return true;
    }
    const std::optional<std::string> rc = o_.stick_program(now - *program_start_ns_);
    if (!rc) {
      stop_stick_program(now, "complete");
      begin_land(o_.mode + " complete", 0);
      return true;
    }
    if (!hover_override_) {
      CommandOptions opt;
      opt.tag = kTagPilot;
      driver_->submit(*rc, opt);
    }
    return false;
  }

  void stop_stick_program(TimeNs now, const std::string& event) {
    program_start_ns_.reset();
    program_done_ = true;
    log_.write(now, "stick_program", {{"event", event}});
  }

  void record(const VideoFrame& f) {
    char name[64];
    std::snprintf(name, sizeof name, "frame_%06lld%s.png", static_cast<long long>(f.index), f.damaged ? "_damaged" : "");
    if (!cv::imwrite((std::filesystem::path(o_.record_dir) / name).string(), f.bgr, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
      log_.write(clock_.now_ns(), "failsafe", {{"event", "cannot record frame " + std::string(name)}});
    }
  }

  void submit_fsw(const std::vector<SdkCommand>& commands) {
    for (const SdkCommand& c : commands) {
      const bool rc = c.text.rfind("rc ", 0) == 0;
      const TimeNs now = clock_.now_ns();
      // No takeoff without a live state stream: the program's failsafes need it in the air
      // (and the flight software's battery check needs it before). Its own timeout retries.
      const bool blind_takeoff =
          c.text == "takeoff" &&
          (!last_state_ns_ || now - *last_state_ns_ > seconds_to_ns(o_.failsafes.state_timeout_s));
      if (rc && program_start_ns_) continue;  // the stick program flies (its rc lines say what)
      if (landing_ || (rc && hover_override_) || blind_takeoff) {
        log_.write(now, "fsw_command_ignored",
                   {{"text", c.text},
                    {"why", landing_         ? "program failsafe landing"
                            : blind_takeoff ? "no recent state record: takeoff withheld"
                                            : "program failsafe hover"}});
        continue;
      }
      const auto& t = o_.flight.timeouts;
      CommandOptions opt;
      opt.tag = kTagFlightSoftware;
      opt.retries = 0;  // the flight software retries on its own (its SdkLink)
      opt.timeout_ns = seconds_to_ns(c.text == "takeoff" ? t.takeoff_reply_s
                                     : c.text == "land"  ? t.land_reply_s
                                                         : t.command_reply_s);
      log_.write(clock_.now_ns(), "fsw_command", {{"text", c.text}, {"fsw_t_ns", c.t_ns}});
      driver_->submit(c.text, opt);
    }
  }

  void log_event(const DriverEvent& e) {
    nlohmann::json j = nlohmann::json::object();
    if (!e.command.empty()) j["command"] = e.command;
    if (e.kind == DriverEvent::Kind::State) {
      j["raw"] = e.reply;
      j["battery_pct"] = e.state->battery_pct;
      j["height_m"] = e.state->height_m;
    } else if (!e.reply.empty()) {
      j["reply"] = e.reply;
    }
    if (e.attempt) j["attempt"] = e.attempt;
    if (e.tag) j["origin"] = origin_name(e.tag);
    if (e.synthetic) j["synthetic"] = true;
    log_.write(e.t_ns, event_kind_name(e.kind), std::move(j));
  }

  void log_telemetry() {
    const auto& tm = fsw_.telemetry();
    if (tm.phase == logged_phase_ && tm.event == logged_event_) return;
    logged_phase_ = tm.phase;
    logged_event_ = tm.event;
    log_.write(clock_.now_ns(), "fsw", {{"phase", flight_sw::phase_name(tm.phase)}, {"event", tm.event},
                                        {"battery_pct", tm.battery_pct}, {"height_m", tm.height_m}});
    if (o_.console) {
      *o_.console << "[" << ns_to_seconds(clock_.now_ns()) << " s] " << flight_sw::phase_name(tm.phase) << ": "
                  << tm.event << std::endl;
    }
  }

  // What the flight software made of each frame of the approach: where it believes it is
  // relative to the target cell (frame K: x toward the shelf, y left, z up; origin at the
  // cell's centre on the front face), so that a flight can be understood afterwards.
  void log_approach_view() {
    const auto& tm = fsw_.telemetry();
    if (tm.phase != flight_sw::Phase::Approach) return;
    nlohmann::json j = {{"tracker_ok", tm.tracker_ok}, {"e_z_m", tm.e_z_m}, {"e_psi_rad", tm.e_psi_rad},
                        {"settled", tm.settled}, {"holding_short", tm.holding_short},
                        {"rejected_poses", tm.rejected_poses}, {"wrong_level_poses", tm.wrong_level_poses},
                        {"damaged_frames", tm.damaged_frames}, {"band_decided_frames", tm.band_decided_frames},
                        {"unflown_frames", tm.unflown_frames}};
    if (tm.pose && tm.pose_in_cell_frame) {
      const Eigen::Vector3d p = tm.pose->p_FB_m();
      j["p_KB_m"] = {p.x(), p.y(), p.z()};
      j["yaw_K_rad"] = tm.pose->yaw_rad;
    }
    if (tm.tracked_box_px) {
      const cv::Rect2d& b = *tm.tracked_box_px;
      j["box_px"] = {b.x, b.y, b.width, b.height};
    }
    log_.write(clock_.now_ns(), "fsw_view", std::move(j));
  }

  // Starts the program's landing; the program then exits with `code` (once landed).
  void begin_land(const std::string& reason, int code) {
    if (landing_) return;
    landing_ = true;
    stop_code_ = code;
    const TimeNs now = clock_.now_ns();
    log_.write(now, "failsafe", {{"event", "land"}, {"reason", reason}, {"airborne", airborne_}});
    failsafe_reason_ = reason;
    if (o_.console) *o_.console << "tello_pilot: " << reason << (airborne_ ? ": landing" : "") << std::endl;
    if (!airborne_) {
      land_done_ = true;
      land_ok_ = true;
      return;
    }
    CommandOptions opt;
    opt.tag = kTagPilot;
    opt.urgent = true;
    opt.retries = 3;
    opt.retry_unless_ok = true;  // "error Not joystick" to a land: ask again, never give up at once
    opt.timeout_ns = seconds_to_ns(o_.failsafes.land_reply_s);
    driver_->submit("land", opt);
  }

  // The program's own failsafes; an exit code when the loop is to end.
  std::optional<int> supervise(int signals) {
    const TimeNs now = clock_.now_ns();
    const Failsafes& f = o_.failsafes;
    if (landing_) {
      if (signals > signals_seen_) {
        signals_seen_ = signals;
        log_.write(now, "failsafe", {{"event", "signal while landing: still waiting for the land reply"}});
      }
      if (!land_done_) return std::nullopt;
      if (!land_ok_) {
        if (o_.console) {
          *o_.console << "tello_pilot: land not acknowledged; the drone's own watchdog lands it within 15 s "
                         "of the last command"
                      << std::endl;
        }
        return 1;
      }
      return stop_code_;
    }
    if (signals > 0) {
      signals_seen_ = signals;
      begin_land("stopped by a signal", airborne_ ? 0 : 130);
      return std::nullopt;
    }
    if (!last_state_ns_ && now - start_ns_ > seconds_to_ns(f.state_start_timeout_s)) {
      if (o_.console) {
        *o_.console << "tello_pilot: no state record from " << o_.driver.drone_ip << " within "
                    << f.state_start_timeout_s << " s: is the computer on the Tello's Wi-Fi, UDP port "
                    << driver_->local_state_port()
                    << " open in the firewall and free (no other Tello program running)?" << std::endl;
      }
      begin_land("no state record since the start", 1);
      return std::nullopt;
    }
    if (airborne_) {
      if (last_state_ns_ && now - *last_state_ns_ > seconds_to_ns(f.state_timeout_s)) {
        begin_land("no state record for " + std::to_string(f.state_timeout_s) + " s", 1);
        return std::nullopt;
      }
      if (battery_pct_ >= 0 && battery_pct_ <= f.critical_battery_pct) {
        begin_land("battery critical (" + std::to_string(battery_pct_) + "%)", 1);
        return std::nullopt;
      }
      if (now - airborne_since_ns_ > seconds_to_ns(f.max_flight_s)) {
        begin_land("maximum flight time reached", 1);
        return std::nullopt;
      }
      const TimeNs since_frame = now - std::max(last_frame_ns_.value_or(0), airborne_since_ns_);
      if (since_frame > seconds_to_ns(f.video_land_s)) {
        begin_land("no video frame for " + std::to_string(f.video_land_s) + " s", 1);
        return std::nullopt;
      }
      if (since_frame > seconds_to_ns(f.video_hover_s)) {
        if (!hover_override_) {
          hover_override_ = true;
          log_.write(now, "failsafe", {{"event", "video stalled: hovering"}});
        }
        CommandOptions opt;
        opt.tag = kTagPilot;
        driver_->submit("rc 0 0 0 0", opt);
      }
      if (fly_stick_program(now)) return std::nullopt;
    }
    if (fsw_.finished()) {
      const int code = fsw_.result().outcome == flight_sw::Outcome::Aborted ? 1 : 0;
      // The flight software found the drone down by the state height (its `land` reply lost):
      // the program agrees when its own newest height does.
      if (airborne_ && fsw_.result().landed && grounded()) airborne_ = false;
      if (airborne_) {
        begin_land("the flight software ended while airborne", code);
        return std::nullopt;
      }
      return code;
    }
    return std::nullopt;
  }

  std::string finish(int code) {
    const TimeNs now = clock_.now_ns();
    const flight_sw::MissionResult r = fsw_.result();
    const std::string driver_counters = driver_->counters().text();
    const std::string video_counters = video_->stats().text();
    const flight_sw::Telemetry& tm = fsw_.telemetry();
    log_.write(now, "end", {{"exit_code", code},
                            {"outcome", flight_sw::outcome_name(r.outcome)},
                            {"reason", r.reason},
                            {"phase", flight_sw::phase_name(fsw_.phase())},
                            {"driver", driver_counters},
                            {"video", video_counters},
                            {"fsw_damaged_frames", tm.damaged_frames},
                            {"fsw_band_decided_frames", tm.band_decided_frames},
                            {"fsw_unflown_frames", tm.unflown_frames},
                            {"fsw_hidden_target_pictures", tm.hidden_target_pictures},
                            {"fsw_rejected_poses", tm.rejected_poses},
                            {"fsw_wrong_level_poses", tm.wrong_level_poses},
                            {"fsw_stale_replies", tm.stale_replies},
                            {"fsw_bad_frames", tm.bad_frames}});
    std::ostringstream summary;
    summary << flight_sw::outcome_name(r.outcome) << (r.reason.empty() ? "" : ": ") << r.reason
            << "\n  driver: " << driver_counters << "\n  video: " << video_counters
            << "\n  flight software: damaged_frames=" << tm.damaged_frames
            << " band_decided_frames=" << tm.band_decided_frames << " unflown_frames=" << tm.unflown_frames
            << " hidden_target_pictures=" << tm.hidden_target_pictures
            << " rejected_poses=" << tm.rejected_poses << " wrong_level_poses=" << tm.wrong_level_poses;
    return summary.str();
  }

  const flight_sw::FlightSoftware& fsw() const { return fsw_; }
  const SdkDriver& driver() const { return *driver_; }
  const VideoReceiver& video() const { return *video_; }
  bool airborne() const { return airborne_; }
  /// The newest state record puts the drone on the ground: at or below the flight software's
  /// own airborne height (mission.airborne_height_m), so that the two agree on "down".
  bool grounded() const { return last_height_m_ && *last_height_m_ <= airborne_height_m(); }
  double airborne_height_m() const { return fsw_.config().mission.airborne_height_m; }
  const std::string& failsafe_reason() const { return failsafe_reason_; }

 private:
  const PilotLoopConfig& o_;
  const Clock& clock_;
  FlightLog log_;
  flight_sw::FlightSoftware fsw_;
  std::unique_ptr<SdkDriver> driver_;
  std::unique_ptr<VideoReceiver> video_;

  TimeNs start_ns_ = 0;
  TimeNs last_fed_ns_ = 0;
  TimeNs last_tick_ns_ = 0;
  static constexpr TimeNs kTickPeriodNs = kNsPerSecond / 20;
  std::optional<TimeNs> last_state_ns_;
  std::optional<TimeNs> last_frame_ns_;
  int battery_pct_ = -1;
  std::optional<double> last_height_m_;
  bool airborne_ = false;
  TimeNs airborne_since_ns_ = 0;
  bool hover_override_ = false;
  std::optional<TimeNs> program_start_ns_;  ///< the stick program flies since
  bool program_done_ = false;
  bool landing_ = false;
  bool land_done_ = false;
  bool land_ok_ = false;
  int stop_code_ = 0;
  int signals_seen_ = 0;
  std::string failsafe_reason_;
  flight_sw::Phase logged_phase_ = flight_sw::Phase::Idle;
  std::string logged_event_;
};

PilotLoop::PilotLoop(const PilotLoopConfig& config, const Clock& clock, PilotChannels channels)
    : impl_(std::make_unique<Impl>(config, clock, std::move(channels))) {}
PilotLoop::~PilotLoop() = default;
void PilotLoop::start() { impl_->start(); }
std::optional<int> PilotLoop::step(int signals) { return impl_->step(signals); }
std::string PilotLoop::finish(int code) { return impl_->finish(code); }
int PilotLoop::command_fd() const { return impl_->driver().command_fd(); }
int PilotLoop::state_fd() const { return impl_->driver().state_fd(); }
int PilotLoop::video_fd() const { return impl_->video().notify_fd(); }
const flight_sw::FlightSoftware& PilotLoop::flight_software() const { return impl_->fsw(); }
const SdkDriver& PilotLoop::driver() const { return impl_->driver(); }
VideoStats PilotLoop::video_stats() const { return impl_->video().stats(); }
std::uint16_t PilotLoop::video_port() const { return impl_->video().local_port(); }
bool PilotLoop::airborne() const { return impl_->airborne(); }
const std::string& PilotLoop::failsafe_reason() const { return impl_->failsafe_reason(); }

}  // namespace shelfcross::tello
