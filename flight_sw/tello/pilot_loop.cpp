#include "flight_sw/tello/pilot_loop.hpp"

#include <algorithm>
#include <ostream>
#include <sstream>
#include <variant>

#include "flight_sw/control/stick_response.hpp"
#include "flight_sw/tello/drone_watch.hpp"
#include "flight_sw/tello/link_watch.hpp"
#include "flight_sw/tello/pilot_log.hpp"
#include "flight_sw/tello/stick_program.hpp"
#include "sdk/command.hpp"

namespace shelfcross::tello {
namespace {

// The longest the driver waits for the reply to one `land` datagram of the flight software
// before it sends it again (fsw_command_options): longer than a landing from cruise height.
constexpr double kLandAttempt_s = 4.0;

// How the driver carries one of the flight software's commands. The flight software retries
// on its own (MissionCommands), so the driver sends each once and times it out at the
// flight software's reply timeout. Except `land`: the flight software's ask lasts
// land_reply_s (10 s, the longest a landing may take), and while the driver holds it a
// lost `land` datagram would leave the drone hovering all that time. So the driver re-sends
// it every kLandAttempt_s within that bound, and sooner when the state records show no
// descent (DroneWatch::land_unheard, in step()). A landing from the highest cruise height
// (about 1.7 m) at the Tello's 0.5 m/s lasts about 3.4 s, so a re-sent `land` reaches a
// drone that got the first one on the ground or still landing: it answers `error`, and the
// flight software ends the landing on the state height (CommandPhases).
CommandOptions fsw_command_options(const std::string& text, const flight_sw::Timeouts& t) {
  CommandOptions opt;
  opt.tag = kTagFlightSoftware;
  opt.retries = 0;
  opt.timeout_ns = seconds_to_ns(text == "takeoff" ? t.takeoff_reply_s : t.command_reply_s);
  if (text == "land") {
    const int attempts = std::max(1, static_cast<int>(t.land_reply_s / kLandAttempt_s));
    opt.retries = attempts - 1;
    opt.timeout_ns = seconds_to_ns(t.land_reply_s / attempts);
  }
  return opt;
}

// Seconds for people and reasons: "10", "2.5".
std::string seconds_text(double s) {
  std::ostringstream os;
  os << s;
  return os.str();
}

DriverConfig driver_config(const PilotLoopConfig& c) {
  DriverConfig dc = c.driver;
  // Keep a stick setpoint alive at least as long as the flight software may go without
  // renewing it (its keep-alive), plus margin.
  dc.rc_hold_ns = std::max(dc.rc_hold_ns, seconds_to_ns(c.flight.rc.keepalive_s + 0.5));
  dc.command_gap_ns = std::max(dc.command_gap_ns, seconds_to_ns(c.flight.timeouts.command_gap_s));
  return dc;
}

// The order in which the flight software gets its inputs: by their clock stamps, which never
// go backwards; and the flight computer's timer: with nothing else to hand over, a tick every
// 50 ms lets the flight software's timeouts and retries fire (a lost first "command" is resent).
class InputFeed {
 public:
  static constexpr TimeNs kTickPeriodNs = kNsPerSecond / 20;

  void start(TimeNs now) { last_tick_ns_ = now; }
  /// Adds a tick to empty `inputs` when one is due at now; sorts them by stamp.
  void prepare(std::vector<flight_sw::Input>& inputs, TimeNs now) {
    if (inputs.empty() && now - last_tick_ns_ >= kTickPeriodNs) {
      last_tick_ns_ = now;
      inputs.emplace_back(flight_sw::ClockTick{now});
    }
    std::stable_sort(inputs.begin(), inputs.end(), [](const auto& a, const auto& b) { return stamp(a) < stamp(b); });
  }
  /// Raises the input's stamp to the last one fed (a frame decoded on the receiver thread may
  /// be stamped just before a state record read earlier in this loop).
  void monotonic(flight_sw::Input& in) {
    std::visit([&](auto& m) { m.t_ns = std::max(m.t_ns, last_fed_ns_); }, in);
    last_fed_ns_ = stamp(in);
  }

 private:
  static TimeNs stamp(const flight_sw::Input& in) {
    return std::visit([](const auto& m) { return m.t_ns; }, in);
  }
  TimeNs last_fed_ns_ = 0;
  TimeNs last_tick_ns_ = 0;
};

// The program's failsafes' state: when the loop started (the state-start timeout counts from
// it), the video hover, the signals seen, and the program's own landing and how it ends.
struct FailsafeState {
  TimeNs started_ns = 0;
  bool hover_override = false;  ///< video stalled: hovering, the flight software's sticks ignored
  int signals_seen = 0;
  bool landing = false;         ///< the program's land is under way
  bool land_done = false;       ///< ... and acknowledged, failed, or not needed
  bool land_ok = false;         ///< ... with the drone down
  int exit_code = 0;            ///< the loop's exit code once landed
  std::string reason;           ///< why the program landed (empty when it did not)
  LinkWatch link{0.0, 0.0};     ///< the link's outages in the air (set from the Failsafes)
};

// The link's verdict on a pass in the air, its loss and return written to the log.
LinkVerdict watch_link(LinkWatch& link, TimeNs now, TimeNs last_state_ns, const Failsafes& f, PilotLog& log,
                       std::ostream* console) {
  const LinkVerdict verdict = link.check(now, last_state_ns);
  if (verdict == LinkVerdict::Lost) {
    log.write(now, "failsafe",
              {{"event", "link lost: hovering"}, {"silent_s", ns_to_seconds(now - last_state_ns)}, {"give_up_s", f.link_outage_s}});
    if (console) *console << "tello_pilot: link lost: hovering (up to " << f.link_outage_s << " s)" << std::endl;
  } else if (verdict == LinkVerdict::Back) {
    log.write(now, "failsafe",
              {{"event", "link back: control returned to the flight software"}, {"outage_s", link.last_outage_s()}});
    if (console) *console << "tello_pilot: link back after " << link.last_outage_s() << " s" << std::endl;
  }
  return verdict;
}

}  // namespace

class PilotLoop::Impl {
 public:
  Impl(const PilotLoopConfig& o, const Clock& clock, PilotChannels channels)
      : o_(o),
        clock_(clock),
        log_(o.log_path, o.console),
        fsw_(o.flight),
        drone_(fsw_.config().mission.airborne_height_m),
        program_(o.stick_program, o.mode, log_, o.console, clock) {
    if (channels.command || channels.state) {
      driver_ = std::make_unique<SdkDriver>(driver_config(o_), clock_, std::move(channels.command),
                                            std::move(channels.state));
    } else {
      driver_ = std::make_unique<SdkDriver>(driver_config(o_), clock_);
    }
    safe_.link = LinkWatch(o.failsafes.state_timeout_s, o.failsafes.link_outage_s);
    video_ = channels.video ? std::make_unique<VideoReceiver>(o_.video, clock_, std::move(channels.video))
                            : std::make_unique<VideoReceiver>(o_.video, clock_);
  }

  void start() {
    const TimeNs start_ns = clock_.now_ns();
    safe_.started_ns = start_ns;
    feed_.start(start_ns);
    log_.write(start_ns, "start",
               {{"drone", o_.driver.drone_ip + ":" + std::to_string(o_.driver.drone_command_port)},
                {"local_command_port", driver_->local_command_port()},
                {"state_port", driver_->local_state_port()},
                {"video_port", video_->local_port()},
                {"dry_run", o_.driver.dry_run},
                {"mode", o_.mode},
                {"flight_config", o_.flight_config_path},
                {"calibration", o_.calibration_path}});
    submit_fsw(fsw_.start(start_ns));
  }

  std::optional<int> step(int signals) {
    video_->service();
    driver_->service();
    step_flight_software();
    if (auto exit_code = supervise(signals)) return exit_code;
    // A `land` the drone did not act on (its datagram lost) goes again at once, not at the end
    // of its reply timeout: the drone hovers meanwhile (DroneWatch::land_unheard).
    if (drone_.land_unheard() && driver_->resend_unheard("land")) {
      log_.write(clock_.now_ns(), "land_unheard", {{"event", "no descent since the land was sent: sent again"}});
    }
    driver_->service();
    return std::nullopt;
  }

  // Driver events -> log and flight-software inputs; the newest frame likewise.
  void step_flight_software() {
    std::vector<flight_sw::Input> inputs;
    for (DriverEvent& e : driver_->take_events()) {
      log_.driver_event(e);
      drone_.on_event(e);
      using K = DriverEvent::Kind;
      if (e.kind == K::State && e.state) {
        inputs.emplace_back(*e.state);
      } else if (e.kind == K::Reply || e.kind == K::Failed) {
        if (e.tag == kTagFlightSoftware && e.kind == K::Reply) inputs.emplace_back(SdkReply{e.t_ns, e.reply});
        if (e.tag == kTagPilot && e.command == "land") {
          safe_.land_done = true;
          safe_.land_ok = accepted(e) || drone_.grounded();
        }
      }
    }
    std::optional<VideoFrame> f = video_->take_latest();
    if (f) {
      const TimeNs taken = clock_.now_ns();
      log_.frame(taken, *f);
      drone_.on_frame(f->handed_ns);
      if (o_.record_frame) log_.record(*f, o_.record_frame, clock_);
      if (safe_.hover_override) {
        safe_.hover_override = false;
        log_.write(taken, "failsafe", {{"event", "video back: control returned to the flight software"}});
      }
      // Damaged (error-concealed) pictures go through, marked: the flight software knows
      // how far to trust them (perception.decide_/steer_max_damage_events).
      inputs.emplace_back(CameraFrame{f->handed_ns, f->index, std::move(f->bgr), f->damaged, f->damage_events,
                                      std::move(f->damaged_rows)});
    }
    feed_.prepare(inputs, clock_.now_ns());
    for (auto& in : inputs) {
      if (fsw_.finished()) break;
      feed_.monotonic(in);
      submit_fsw(fsw_.step(in));
      log_.telemetry(fsw_.telemetry(), clock_);
      program_.start_when_airborne(fsw_.phase());
      if (const auto* frame = std::get_if<CameraFrame>(&in)) {
        log_.approach_view(fsw_.telemetry(), clock_);
        if (o_.on_frame) o_.on_frame(*frame, fsw_);
      }
    }
  }

  void submit_fsw(const std::vector<SdkCommand>& commands) {
    for (const SdkCommand& c : commands) {
      const bool rc = sdk::is_rc_text(c.text);
      const TimeNs now = clock_.now_ns();
      // No takeoff without a live state stream: the program's failsafes need it in the air
      // (and the flight software's battery check needs it before). Its own timeout retries.
      const std::optional<TimeNs> last_state_ns = drone_.last_state_ns();
      const bool blind_takeoff =
          c.text == "takeoff" &&
          (!last_state_ns || now - *last_state_ns > seconds_to_ns(o_.failsafes.state_timeout_s));
      if (rc && program_.flying()) continue;  // the stick program flies (its rc lines say what)
      const bool hover = safe_.hover_override || safe_.link.out();
      if (safe_.landing || (rc && hover) || blind_takeoff) {
        log_.write(now, "fsw_command_ignored",
                   {{"text", c.text},
                    {"why", safe_.landing      ? "program failsafe landing"
                            : blind_takeoff    ? "no recent state record: takeoff withheld"
                            : safe_.link.out() ? "program failsafe hover: link out"
                                               : "program failsafe hover"}});
        continue;
      }
      log_.write(clock_.now_ns(), "fsw_command", {{"text", c.text}, {"fsw_t_ns", c.t_ns}});
      driver_->submit(c.text, fsw_command_options(c.text, o_.flight.timeouts));
    }
  }

  // Starts the program's landing; the program then exits with `code` (once landed).
  void begin_land(const std::string& reason, int code) {
    if (safe_.landing) return;
    safe_.landing = true;
    safe_.exit_code = code;
    const TimeNs now = clock_.now_ns();
    const bool airborne = drone_.airborne();
    log_.write(now, "failsafe", {{"event", "land"}, {"reason", reason}, {"airborne", airborne}});
    safe_.reason = reason;
    if (o_.console) *o_.console << "tello_pilot: " << reason << (airborne ? ": landing" : "") << std::endl;
    if (!airborne) {
      safe_.land_done = true;
      safe_.land_ok = true;
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
    if (safe_.landing) return landing_outcome(now, signals);
    if (signals > 0) {
      safe_.signals_seen = signals;
      begin_land("stopped by a signal", drone_.airborne() ? 0 : 130);
      return std::nullopt;
    }
    if (!drone_.last_state_ns() && now - safe_.started_ns > seconds_to_ns(f.state_start_timeout_s)) {
      if (o_.console) {
        *o_.console << "tello_pilot: no state record from " << o_.driver.drone_ip << " within "
                    << f.state_start_timeout_s << " s: is the computer on the Tello's Wi-Fi, UDP port "
                    << driver_->local_state_port()
                    << " open in the firewall and free (no other Tello program running)?" << std::endl;
      }
      begin_land("no state record since the start", 1);
      return std::nullopt;
    }
    if (drone_.airborne() && supervise_airborne(now)) return std::nullopt;
    if (fsw_.finished()) {
      const int code = fsw_.result().outcome == flight_sw::Outcome::Aborted ? 1 : 0;
      // The flight software found the drone down by the state height (its `land` reply lost):
      // the program agrees when its own newest height does.
      if (fsw_.result().landed) drone_.landed_if_grounded();
      if (drone_.airborne()) {
        begin_land("the flight software ended while airborne", code);
        return std::nullopt;
      }
      return code;
    }
    return std::nullopt;
  }

  // While the program lands: the exit code once its land is acknowledged or given up.
  std::optional<int> landing_outcome(TimeNs now, int signals) {
    if (signals > safe_.signals_seen) {
      safe_.signals_seen = signals;
      log_.write(now, "failsafe", {{"event", "signal while landing: still waiting for the land reply"}});
    }
    if (!safe_.land_done) return std::nullopt;
    if (!safe_.land_ok) {
      if (o_.console) {
        *o_.console << "tello_pilot: land not acknowledged; the drone's own watchdog lands it within 15 s "
                       "of the last command"
                    << std::endl;
      }
      return 1;
    }
    return safe_.exit_code;
  }

  // The failsafes of the air: the link (ride through an outage, hovering, then land), battery,
  // flight time, video (hover, then land); then the stick program's pass (its sticks, unless
  // hovering). True when a landing began.
  bool supervise_airborne(TimeNs now) {
    const Failsafes& f = o_.failsafes;
    const auto pilot_rc = [this](const std::string& text) {
      CommandOptions opt;
      opt.tag = kTagPilot;
      driver_->submit(text, opt);
    };
    const std::optional<TimeNs> last_state_ns = drone_.last_state_ns();
    if (last_state_ns && watch_link(safe_.link, now, *last_state_ns, f, log_, o_.console) == LinkVerdict::GiveUp) {
      begin_land("no state record for " + seconds_text(f.link_outage_s) + " s: the link is lost", 1);
      return true;
    }
    const int battery_pct = drone_.battery_pct();
    if (battery_pct >= 0 && battery_pct <= f.critical_battery_pct) {
      begin_land("battery critical (" + std::to_string(battery_pct) + "%)", 1);
      return true;
    }
    if (now - drone_.airborne_since_ns() > seconds_to_ns(f.max_flight_s)) {
      begin_land("maximum flight time reached", 1);
      return true;
    }
    // The link out (link_watch.hpp): hover while it lasts, so that the first datagram through
    // stops the drone; the video's timers wait for the link.
    if (safe_.link.out()) {
      pilot_rc("rc 0 0 0 0");
      return false;
    }
    // The video comes back after the link (a key frame first): its timers run from the return.
    const TimeNs since_frame = now - std::max({drone_.last_frame_ns().value_or(0), drone_.airborne_since_ns(),
                                               safe_.link.back_ns().value_or(0)});
    if (since_frame > seconds_to_ns(f.video_land_s)) {
      begin_land("no video frame for " + std::to_string(f.video_land_s) + " s", 1);
      return true;
    }
    if (since_frame > seconds_to_ns(f.video_hover_s)) {
      if (!safe_.hover_override) {
        safe_.hover_override = true;
        log_.write(now, "failsafe", {{"event", "video stalled: hovering"}});
      }
      pilot_rc("rc 0 0 0 0");
    }
    const StickProgramRun::Pass pass = program_.step(now, fsw_);
    if (pass.land_reason) {
      begin_land(*pass.land_reason, pass.exit_code);
      return true;
    }
    if (pass.rc && !safe_.hover_override) pilot_rc(*pass.rc);
    return false;
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
                            {"fsw_damaged_frames", tm.link.damaged_frames},
                            {"fsw_band_decided_frames", tm.link.band_decided_frames},
                            {"fsw_unflown_frames", tm.link.unflown_frames},
                            {"fsw_hidden_target_pictures", tm.tracking.counts.hidden_target_pictures},
                            {"fsw_rejected_poses", tm.tracking.counts.rejected_poses},
                            {"fsw_wrong_level_poses", tm.tracking.counts.wrong_level_poses},
                            {"fsw_level_unsure_poses", tm.tracking.counts.level_unsure_poses},
                            {"fsw_stale_replies", tm.link.stale_replies},
                            {"fsw_bad_frames", tm.link.bad_frames},
                            {"fsw_sticks", flight_sw::stick_response_text(tm.control.sticks)}});
    std::ostringstream summary;
    summary << flight_sw::outcome_name(r.outcome) << (r.reason.empty() ? "" : ": ") << r.reason
            << "\n  driver: " << driver_counters << "\n  video: " << video_counters
            << "\n  flight software: damaged_frames=" << tm.link.damaged_frames
            << " band_decided_frames=" << tm.link.band_decided_frames << " unflown_frames=" << tm.link.unflown_frames
            << " hidden_target_pictures=" << tm.tracking.counts.hidden_target_pictures
            << " rejected_poses=" << tm.tracking.counts.rejected_poses << " wrong_level_poses=" << tm.tracking.counts.wrong_level_poses
            << " level_unsure_poses=" << tm.tracking.counts.level_unsure_poses
            << "\n  the Tello's answer to its sticks, times nominal: "
            << flight_sw::stick_response_text(tm.control.sticks);
    return summary.str();
  }

  const flight_sw::FlightSoftware& fsw() const { return fsw_; }
  const SdkDriver& driver() const { return *driver_; }
  const VideoReceiver& video() const { return *video_; }
  bool airborne() const { return drone_.airborne(); }
  const std::string& failsafe_reason() const { return safe_.reason; }

 private:
  const PilotLoopConfig& o_;
  const Clock& clock_;
  PilotLog log_;
  flight_sw::FlightSoftware fsw_;
  std::unique_ptr<SdkDriver> driver_;
  std::unique_ptr<VideoReceiver> video_;
  DroneWatch drone_;
  StickProgramRun program_;
  InputFeed feed_;
  FailsafeState safe_;
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
