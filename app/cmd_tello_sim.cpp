// shelfcross tello-sim --scenario FILE [...]: the Tello SDK emulator (verification/world/tello_emulator.hpp)
// on UDP, paced by the wall clock, until the simulated drone has landed after flying, a
// signal (SIGINT, SIGTERM), or --max-seconds. Prints what happened; --report FILE as JSON.
#include <csignal>
#include <fstream>
#include <iostream>
#include <tuple>

#include <opencv2/core.hpp>

#include "command_registry.hpp"
#include "stop_signal.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/tello_emulator.hpp"

namespace shelfcross::app {
namespace {

struct TelloSimOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  verification::EmulatorConfig config;
  std::string video_stall;
  std::string outage;         ///< --outage T,D
  std::string outage_lengths; ///< --outage-lengths MIN,MAX
  double max_seconds = 0.0;
  std::string report;
  bool nominal = false;
  std::string write_calibration;
};

/// The believed camera as an OpenCV calibration file, as tello_pilot --calibration reads it.
void write_calibration(const std::string& path, const CameraIntrinsics& c) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw std::runtime_error("tello-sim: cannot write " + path);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  const cv::Mat d = (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3);
  fs << "image_width" << c.width_px << "image_height" << c.height_px << "camera_matrix" << K
     << "distortion_coefficients" << d;
}

/// "A,B": two numbers; `what` names the option and the numbers for the message.
std::pair<double, double> parse_pair(const std::string& text, const std::string& what) {
  const auto comma = text.find(',');
  try {
    if (comma == std::string::npos) throw std::invalid_argument("");
    std::size_t used_a = 0, used_b = 0;
    const std::string a = text.substr(0, comma), b = text.substr(comma + 1);
    const double first = std::stod(a, &used_a), second = std::stod(b, &used_b);
    if (used_a != a.size() || used_b != b.size()) throw std::invalid_argument("");
    return {first, second};
  } catch (const std::exception&) {
    throw UsageError(what + ", got '" + text + "'");
  }
}

/// The options given as pairs: the video stall, the fixed outage, the random outages' lengths.
void parse_pairs(const TelloSimOptions& o, verification::EmulatorFaults& f) {
  if (!o.video_stall.empty()) {
    std::tie(f.video_stall_start_s.emplace(), f.video_stall_duration_s) =
        parse_pair(o.video_stall, "--video-stall: expected T,D (seconds since the start, duration)");
  }
  if (!o.outage.empty()) {
    std::tie(f.outages.start_s.emplace(), f.outages.duration_s) =
        parse_pair(o.outage, "--outage: expected T,D (seconds since the start, duration)");
  }
  if (!o.outage_lengths.empty()) {
    std::tie(f.outages.min_s, f.outages.max_s) =
        parse_pair(o.outage_lengths, "--outage-lengths: expected MIN,MAX (seconds)");
  }
}

const CommandRegistration kTelloSim{
    "tello-sim",
    "Emulate a Tello on UDP (SDK 1.3/2.0): the simulated drone, world and camera of a scenario, in real time",
    [](CLI::App& sub) {
      auto o = std::make_shared<TelloSimOptions>();
      verification::EmulatorConfig& c = o->config;
      verification::EmulatorFaults& f = c.faults;
      const auto probability = CLI::Range(0.0, 1.0);
      const auto delay = CLI::Range(0.0, 600000.0);
      sub.add_option("--scenario", o->scenario, "scenario file (the world, camera, vehicle)")->capture_default_str();
      sub.add_option("--seed", c.seed,
                     "seed of the scenario's dispersions (as `shelfcross run --seed`), wind, render noise and fault draws")
          ->capture_default_str();
      sub.add_flag("--nominal", o->nominal, "fly the nominal scenario: no dispersion draws");
      sub.add_option("--write-calibration", o->write_calibration,
                     "write the flight software's believed camera of this seed (the dispersed calibration error) "
                     "as an OpenCV calibration file for tello_pilot --calibration");
      sub.add_option("--bind-ip", c.bind_ip, "address of the emulated drone's sockets")->capture_default_str();
      sub.add_option("--command-port", c.command_port, "the drone's command port (0: any free port, printed)")
          ->capture_default_str()->check(CLI::Range(0, 65535));
      sub.add_option("--client-state-port", c.client_state_port, "state goes to this port of the `command` sender")
          ->capture_default_str()->check(CLI::Range(1, 65535));
      sub.add_option("--client-video-port", c.client_video_port, "video goes to this port of the `command` sender")
          ->capture_default_str()->check(CLI::Range(1, 65535));
      sub.add_option("--state-source-port", c.state_source_port, "the drone's state source port (0: any free port)")
          ->capture_default_str()->check(CLI::Range(0, 65535));
      sub.add_option("--video-source-port", c.video_source_port, "the drone's video source port (0: any free port)")
          ->capture_default_str()->check(CLI::Range(0, 65535));
      sub.add_option("--loss-commands", f.commands.loss, "probability that a command datagram is lost")->check(probability);
      sub.add_option("--loss-replies", f.replies.loss, "probability that a reply is lost")->check(probability);
      sub.add_option("--loss-state", f.state.loss, "probability that a state datagram is lost")->check(probability);
      sub.add_option("--loss-video", f.video.loss, "probability that a video datagram is lost")->check(probability);
      sub.add_option("--loss-video-frames", f.video_frame_loss, "probability that a whole video frame is lost")
          ->check(probability);
      sub.add_option("--delay-commands", f.commands.delay_ms, "ms added to every command")->check(delay);
      sub.add_option("--delay-replies", f.replies.delay_ms, "ms added to every reply")->check(delay);
      sub.add_option("--delay-state", f.state.delay_ms, "ms added to every state datagram")->check(delay);
      sub.add_option("--delay-video", f.video.delay_ms, "frames leave no earlier than capture + this (ms)")->check(delay);
      sub.add_option("--late-replies", f.late_replies, "probability that a reply comes --late-reply-ms late")->check(probability);
      sub.add_option("--late-reply-ms", f.late_reply_ms, "how late a late reply is (ms)")->capture_default_str()->check(delay);
      sub.add_option("--duplicate-replies", f.replies.duplicate, "probability that a reply is sent twice")->check(probability);
      sub.add_option("--not-joystick", f.not_joystick, "probability of 'error Not joystick' for a manoeuvre (1: always)")
          ->check(probability);
      sub.add_option("--no-valid-imu", f.no_valid_imu, "probability of 'error No valid imu' for a manoeuvre (1: always)")
          ->check(probability);
      sub.add_option("--video-stall", o->video_stall, "T,D: no frames from T s after the start for D s");
      sub.add_option("--burst-mean", f.bursts.bad_mean_s,
                     "losses in bursts: mean burst length (s; each channel's bad state; 0: no bursts)")
          ->capture_default_str()->check(CLI::Range(0.0, 60.0));
      sub.add_option("--burst-interval", f.bursts.good_mean_s, "mean time between bursts (s; the good state)")
          ->capture_default_str()->check(CLI::Range(0.1, 3600.0));
      sub.add_option("--burst-loss", f.bursts.bad_loss, "probability that a datagram is lost in a burst")
          ->capture_default_str()->check(probability);
      sub.add_option("--outage-interval", f.outages.interval_mean_s,
                     "outages of every channel at random: mean time between them (s; 0: none)")
          ->capture_default_str();
      sub.add_option("--outage-lengths", o->outage_lengths, "MIN,MAX: a random outage lasts uniform in [MIN, MAX] s (1,5)");
      sub.add_option("--outage", o->outage, "T,D: every channel down from T s after the start for D s");
      sub.add_option("--key-interval", c.key_interval_frames,
                     "frames between key frames (0: one per second, as the Tello)")
          ->capture_default_str()->check(CLI::Range(0, 600));
      sub.add_option("--slices", c.slices_per_frame,
                     "slices per picture (bands of macroblock rows; a lost datagram damages the rest of its slice)")
          ->capture_default_str()->check(CLI::Range(1, 45));
      sub.add_option("--linger", c.linger_s, "after landing, end when no datagram came this long (s)")
          ->capture_default_str()->check(CLI::Range(0.0, 3600.0));
      sub.add_option("--max-seconds", o->max_seconds, "end after this long (s; 0: no limit)")
          ->capture_default_str()->check(CLI::Range(0.0, 1e6));
      sub.add_option("--report", o->report, "write the report as JSON to this file");
      return [o]() -> int {
        parse_pairs(*o, o->config.faults);
        try {
          verification::validate_emulator_config(o->config);
        } catch (const std::invalid_argument& e) {
          throw UsageError(e.what());
        }
        const verification::Scenario nominal = verification::load_scenario(o->scenario);
        // The world of this seed, drawn as `shelfcross run --seed` draws it.
        o->config.disperse = !o->nominal;
        verification::TelloEmulator emulator(nominal, o->config);
        const verification::RunSetup& setup = emulator.setup();
        const verification::Scenario& scenario = *setup.scenario;
        if (!o->write_calibration.empty()) write_calibration(o->write_calibration, setup.believed_camera);
        stop_on_signals();
        std::cout << "tello-sim " << scenario.name << " seed " << o->config.seed << ": commands on "
                  << o->config.bind_ip << ":" << emulator.ports().command << ", state from port "
                  << emulator.ports().state_source << " to port " << o->config.client_state_port
                  << ", video from port " << emulator.ports().video_source << " to port "
                  << o->config.client_video_port << "\n"
                  << (o->nominal ? "nominal scenario (no dispersion)\n" : "");
        if (!setup.drawn.empty()) {
          std::cout << "dispersions of seed " << setup.seed << ":";
          for (const auto& [name, value] : setup.drawn) {
            std::cout << " " << name << "=" << value << (verification::emulator_applies_dispersion(name) ? "" : "(not applied)");
          }
          std::cout << "\n(not applied: the link and computer are real here, use --loss-*/--delay-*; the camera "
                       "error is the pilot's belief, see --write-calibration)\n";
        }
        std::cout << "renderer: " << emulator.renderer_description() << std::endl;
        verification::run_tello_emulator(emulator, stop_requested(), o->max_seconds);
        const verification::EmulatorReport report = emulator.report();
        std::cout << verification::emulator_report_text(report) << std::flush;
        if (!o->report.empty()) {
          std::ofstream out(o->report);
          out << verification::emulator_report_json(report) << "\n";
          if (!out) {
            std::cerr << "tello-sim: cannot write " << o->report << "\n";
            return 1;
          }
        }
        return report.end_reason == "numerical_failure" || report.end_reason == "video_error" ? 1 : 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
