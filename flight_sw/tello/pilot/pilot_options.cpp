#include "flight_sw/tello/pilot/pilot_options.hpp"

#include <filesystem>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "config/strict_yaml.hpp"
#include "flight_sw/tello/link_watch.hpp"

namespace shelfcross::tello::pilot {
namespace {

using config::Bounds;

template <class T>
Bounds<T> within(T lo, T hi) {
  return {.min = lo, .max = hi, .min_exclusive = false, .max_exclusive = false};
}
const Bounds<double> kPositive{.min = 0.0, .max = std::nullopt, .min_exclusive = true, .max_exclusive = false};
const Bounds<int> kPort = within(0, 65535);
// A link outage is ridden through for at most the Tello's watchdog less the driver's keep-alive
// period (link_watch.hpp): 10 s.
const double kLongestOutage_s = LinkWatch::longest_outage_s(ns_to_seconds(DriverConfig{}.keepalive_ns));
const Bounds<double> kLinkOutage{.min = 0.0, .max = kLongestOutage_s, .min_exclusive = true, .max_exclusive = false};

std::uint16_t port(int p) { return static_cast<std::uint16_t>(p); }

// A path in a pilot file is relative to that file.
std::string relative_to(const std::string& file, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(file).parent_path() / path).string();
}

const char* damaged_name(DamagedFrames d) { return d == DamagedFrames::conceal ? "conceal" : "discard"; }

template <class Fail>
DamagedFrames parse_damaged(const std::string& text, Fail fail) {
  if (text == "conceal") return DamagedFrames::conceal;
  if (text == "discard") return DamagedFrames::discard;
  fail("expected conceal or discard, got '" + text + "'");
  return DamagedFrames::conceal;
}

// The pilot file: every key optional, see flight_sw/tello/README.md.
void read_pilot_file(const std::string& path, PilotOptions& o) {
  const auto doc = config::Document::from_file(path);
  const config::Map root = doc.root();
  if (auto link = root.optional_map("link")) {
    o.driver.drone_ip = link->optional<std::string>("drone_ip", o.driver.drone_ip);
    o.driver.drone_command_port = port(link->optional<int>("command_port", o.driver.drone_command_port, kPort));
    o.driver.local_ip = link->optional<std::string>("local_ip", o.driver.local_ip);
    o.driver.local_command_port =
        port(link->optional<int>("local_command_port", o.driver.local_command_port, kPort));
    o.driver.local_state_port = port(link->optional<int>("state_port", o.driver.local_state_port, kPort));
    o.driver.state_source_port =
        port(link->optional<int>("state_source_port", o.driver.state_source_port, kPort));
    o.video.local_port = port(link->optional<int>("video_port", o.video.local_port, kPort));
    o.video.source_port = port(link->optional<int>("video_source_port", o.video.source_port, kPort));
    link->finish();
  }
  if (auto f = root.optional_map("failsafes")) {
    Failsafes& s = o.failsafes;
    s.state_timeout_s = f->optional<double>("state_timeout_s", s.state_timeout_s, kPositive);
    s.link_outage_s = f->optional<double>("link_outage_s", s.link_outage_s, kLinkOutage);
    s.state_start_timeout_s = f->optional<double>("state_start_timeout_s", s.state_start_timeout_s, kPositive);
    s.video_hover_s = f->optional<double>("video_hover_s", s.video_hover_s, kPositive);
    s.video_land_s = f->optional<double>("video_land_s", s.video_land_s, kPositive);
    s.critical_battery_pct = f->optional<int>("critical_battery_pct", s.critical_battery_pct, within(0, 100));
    s.max_flight_s = f->optional<double>("max_flight_s", s.max_flight_s, kPositive);
    s.land_reply_s = f->optional<double>("land_reply_s", s.land_reply_s, kPositive);
    if (s.video_land_s < s.video_hover_s) f->fail("video_land_s", "must not be shorter than video_hover_s");
    if (s.link_outage_s < s.state_timeout_s) f->fail("link_outage_s", "must not be shorter than state_timeout_s");
    f->finish();
  }
  if (auto v = root.optional_map("video")) {
    o.video.damaged = parse_damaged(v->optional<std::string>("damaged_frames", damaged_name(o.video.damaged)),
                                    [&](const std::string& why) { v->fail("damaged_frames", why); });
    v->finish();
  }
  if (auto out = root.optional_map("output")) {
    o.log_path = relative_to(path, out->optional<std::string>("log", o.log_path));
    o.inventory_path = relative_to(path, out->optional<std::string>("inventory", o.inventory_path));
    out->finish();
  }
  o.flight_config_path = relative_to(path, root.optional<std::string>("flight_config", o.flight_config_path));
  o.calibration_path = relative_to(path, root.optional<std::string>("calibration", o.calibration_path));
  o.dry_run = root.optional<bool>("dry_run", o.dry_run);
  root.finish();
}

}  // namespace

CameraIntrinsics load_calibration(const std::string& path) {
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ)) throw UsageError(path + ": cannot open the calibration file");
  } catch (const cv::Exception& e) {
    throw UsageError(path + ": not an OpenCV calibration file (" + e.msg + ")");
  }
  auto fail = [&](const std::string& why) { return UsageError(path + ": " + why); };
  cv::Mat K, dist;
  int width = 0, height = 0;
  try {
    fs["camera_matrix"] >> K;
    fs["distortion_coefficients"] >> dist;
    fs["image_width"] >> width;
    fs["image_height"] >> height;
  } catch (const cv::Exception& e) {
    throw fail("unreadable entry (" + e.msg + ")");
  }
  if (K.empty() || K.rows != 3 || K.cols != 3) throw fail("camera_matrix missing or not 3x3");
  if (dist.empty() || dist.total() < 4) throw fail("distortion_coefficients missing (k1 k2 p1 p2 [k3])");
  if (width <= 0 || height <= 0) throw fail("image_width and image_height missing");
  K.convertTo(K, CV_64F);
  dist.convertTo(dist, CV_64F);
  const double* d = dist.ptr<double>();
  CameraIntrinsics c;
  c.width_px = width;
  c.height_px = height;
  c.fx_px = K.at<double>(0, 0);
  c.fy_px = K.at<double>(1, 1);
  c.cx_px = K.at<double>(0, 2);
  c.cy_px = K.at<double>(1, 2);
  c.k1 = d[0];
  c.k2 = d[1];
  c.p1 = d[2];
  c.p2 = d[3];
  c.k3 = dist.total() >= 5 ? d[4] : 0.0;
  if (!(c.fx_px > 0 && c.fy_px > 0 && c.cx_px > 0 && c.cx_px < width && c.cy_px > 0 && c.cy_px < height)) {
    throw fail("camera_matrix implausible (focal lengths must be > 0, principal point inside the image)");
  }
  return c;
}

namespace {

// The command line's values, kept apart from the options: they win over the pilot file, which
// is read after the command line is parsed (an option's count() says it was given).
struct CommandLine {
  std::string pilot_file, drone_ip, local_ip, log_path, inventory_path, damaged, board, marker_ids;
  int command_port = 0, local_command_port = 0, state_port = 0, video_port = 0;
  int state_source_port = 0, video_source_port = 0;
  Failsafes fs;
  CLI::Option *ip = nullptr, *cport = nullptr, *lip = nullptr, *lcport = nullptr, *sport = nullptr,
              *vport = nullptr, *ssport = nullptr, *vsport = nullptr, *log = nullptr, *inv = nullptr,
              *damaged_video = nullptr;
  CLI::Option *st = nullptr, *lo = nullptr, *sst = nullptr, *vh = nullptr, *vl = nullptr, *bat = nullptr, *max = nullptr;
  double mission_s = 0.0;
  CLI::Option* budget = nullptr;
};

// The options of a flight: files, the link, the outputs, the modes (--help lists them in this order).
void add_flight_options(CLI::App& app, PilotOptions& o, CommandLine& c) {
  app.add_option("--pilot", c.pilot_file, "pilot YAML file (link, failsafes, output, flight_config, calibration, dry_run)")
      ->check(CLI::ExistingFile);
  app.add_option("--config", o.flight_config_path, "flight-software YAML (flight_sw/README.md)");
  app.add_option("--calibration", o.calibration_path,
                 "OpenCV camera calibration (camera_matrix, distortion_coefficients); replaces the config's camera");
  c.ip = app.add_option("--drone-ip", c.drone_ip, "the Tello's address (default 192.168.10.1)");
  c.cport = app.add_option("--command-port", c.command_port, "the drone's command port (default 8889)")->check(CLI::Range(1, 65535));
  c.lip = app.add_option("--local-ip", c.local_ip, "local address to bind (default 0.0.0.0)");
  c.lcport = app.add_option("--local-command-port", c.local_command_port, "local command port (default 0: any)")->check(CLI::Range(0, 65535));
  c.sport = app.add_option("--state-port", c.state_port, "local state port (default 8890)")->check(CLI::Range(0, 65535));
  c.vport = app.add_option("--video-port", c.video_port, "local video port (default 11111)")->check(CLI::Range(0, 65535));
  c.ssport = app.add_option("--state-source-port", c.state_source_port, "accept state only from this drone port (default 0: any)")->check(CLI::Range(0, 65535));
  c.vsport = app.add_option("--video-source-port", c.video_source_port, "accept video only from this drone port (default 0: any)")->check(CLI::Range(0, 65535));
  c.log = app.add_option("--log", c.log_path, "flight log, JSON lines (default tello_flight_log.jsonl)");
  c.inv = app.add_option("--inventory", c.inventory_path, "inventory JSON output (default tello_inventory.json)");
  c.damaged_video = app.add_option("--damaged-video", c.damaged,
                                   "damaged frames (lost datagrams): conceal (hand over error-concealed pictures, default) or discard (until the next clean key frame)");
  app.add_option("--record-frames", o.record_dir,
                 "write every frame handed to the flight software to this folder as frame_INDEX[_damaged].png (costs time)");
  app.add_flag("--dry-run", o.dry_run, "connect, stream and run perception; never send a motion command");
  app.add_flag("--fly-calibration", o.fly_calibration,
               "fly the calibration manoeuvre (pulses and doublets of each stick, about 48 s, in open space) instead of the mission, "
               "then land: its --log is for `shelfcross identify`");
  app.add_option("--senses-board", o.senses_board_m,
                 "with --fly-calibration: first a still hover and a slow pass over a board whose middle lies this far (m, 1.0..2.5) "
                 "straight behind the take-off point (docs/calibration.md); its height goes to `shelfcross identify --board-height`")
      ->check(CLI::Range(1.0, 2.5));
}

void add_failsafe_options(CLI::App& app, CommandLine& c) {
  Failsafes& fs = c.fs;
  c.st = app.add_option("--state-timeout", fs.state_timeout_s,
                        "airborne without state this long (s): the link is out, hover and wait for it")
             ->check(CLI::PositiveNumber);
  c.lo = app.add_option("--link-outage", fs.link_outage_s,
                        "airborne without state this long (s, at most the Tello's 15 s watchdog less the 5 s keep-alive): land")
             ->check(CLI::PositiveNumber & CLI::Range(0.0, kLongestOutage_s));
  c.sst = app.add_option("--state-start-timeout", fs.state_start_timeout_s, "no state at all this long after start (s): give up")->check(CLI::PositiveNumber);
  c.vh = app.add_option("--video-hover", fs.video_hover_s, "airborne without frames this long (s): hover")->check(CLI::PositiveNumber);
  c.vl = app.add_option("--video-land", fs.video_land_s, "airborne without frames this long (s): land")->check(CLI::PositiveNumber);
  c.bat = app.add_option("--critical-battery", fs.critical_battery_pct, "battery at or below this (%): land")->check(CLI::Range(0, 100));
  c.max = app.add_option("--max-flight", fs.max_flight_s, "airborne this long (s): land")->check(CLI::PositiveNumber);
  c.budget = app.add_option("--mission-budget", c.mission_s,
                            "the flight software's mission budget from its start (s; replaces the configuration's "
                            "timeouts.mission_s): then it gives up where safe and lands, 'mission time limit reached'")
                 ->check(CLI::PositiveNumber);
}

// The modes that do not fly the mission: calibrating the camera, printing markers.
void add_tool_options(CLI::App& app, PilotOptions& o, CommandLine& c) {
  app.add_option("--calibrate", o.calibrate_path, "calibration mode: record chessboard views from the stream, write intrinsics to this file, exit (no motion)");
  app.add_option("--board", c.board, "calibration chessboard inner corners, COLSxROWS (default 9x6)");
  app.add_option("--square", o.square_m, "calibration chessboard square side (m, default 0.025)")->check(CLI::PositiveNumber);
  app.add_option("--views", o.calibration_views, "calibration views to collect (default 25)")->check(CLI::Range(5, 200));
  app.add_option("--print-markers", o.print_dir, "print mode: write marker and tag PNGs (300 dpi) of the flight configuration to this folder, exit");
  app.add_option("--marker-ids", c.marker_ids, "markers to print, FIRST-LAST (default 0-15)");
}

// The command line wins over the pilot file.
void apply_command_line(const CommandLine& c, PilotOptions& o) {
  if (c.ip->count()) o.driver.drone_ip = c.drone_ip;
  if (c.cport->count()) o.driver.drone_command_port = port(c.command_port);
  if (c.lip->count()) o.driver.local_ip = c.local_ip;
  if (c.lcport->count()) o.driver.local_command_port = port(c.local_command_port);
  if (c.sport->count()) o.driver.local_state_port = port(c.state_port);
  if (c.vport->count()) o.video.local_port = port(c.video_port);
  if (c.ssport->count()) o.driver.state_source_port = port(c.state_source_port);
  if (c.vsport->count()) o.video.source_port = port(c.video_source_port);
  if (c.log->count()) o.log_path = c.log_path;
  if (c.inv->count()) o.inventory_path = c.inventory_path;
  if (c.damaged_video->count()) {
    o.video.damaged = parse_damaged(c.damaged, [](const std::string& why) -> void { throw UsageError("--damaged-video: " + why); });
  }
  if (c.st->count()) o.failsafes.state_timeout_s = c.fs.state_timeout_s;
  if (c.lo->count()) o.failsafes.link_outage_s = c.fs.link_outage_s;
  if (c.sst->count()) o.failsafes.state_start_timeout_s = c.fs.state_start_timeout_s;
  if (c.vh->count()) o.failsafes.video_hover_s = c.fs.video_hover_s;
  if (c.vl->count()) o.failsafes.video_land_s = c.fs.video_land_s;
  if (c.bat->count()) o.failsafes.critical_battery_pct = c.fs.critical_battery_pct;
  if (c.max->count()) o.failsafes.max_flight_s = c.fs.max_flight_s;
}

// --board COLSxROWS and --marker-ids FIRST-LAST, when given.
void parse_board_and_markers(const CommandLine& c, PilotOptions& o) {
  if (!c.board.empty()) {
    int cols = 0, rows = 0;
    char x = 0;
    std::istringstream in(c.board);
    if (!(in >> cols >> x >> rows) || x != 'x' || cols < 3 || rows < 3 || !in.eof()) {
      throw UsageError("--board '" + c.board + "': expected COLSxROWS inner corners, each >= 3 (e.g. 9x6)");
    }
    o.board_columns = cols;
    o.board_rows = rows;
  }
  if (!c.marker_ids.empty()) {
    int first = -1, last = -1;
    char dash = 0;
    std::istringstream in(c.marker_ids);
    if (!(in >> first >> dash >> last) || dash != '-' || first < 0 || last < first || !in.eof()) {
      throw UsageError("--marker-ids '" + c.marker_ids + "': expected FIRST-LAST (e.g. 0-15)");
    }
    o.marker_first = first;
    o.marker_last = last;
  }
}

// The flight configuration (required to fly, optional to calibrate) and the camera calibration
// that replaces its camera.
void load_flight_files(PilotOptions& o) {
  if (o.flight_config_path.empty() && o.calibrate_path.empty()) {
    throw UsageError("no flight configuration: give --config FILE (or flight_config: in the --pilot file)");
  }
  if (!o.flight_config_path.empty()) {
    try {
      o.flight = flight_sw::load_flight_config(o.flight_config_path);
    } catch (const config::ConfigError& e) {
      throw UsageError(e.what());
    } catch (const std::exception& e) {
      throw UsageError(o.flight_config_path + ": " + e.what());
    }
  }
  if (!o.calibration_path.empty() && o.calibrate_path.empty()) {
    o.flight.camera = load_calibration(o.calibration_path);
    try {
      flight_sw::validate_flight_config(o.flight);
    } catch (const std::exception& e) {
      throw UsageError(o.calibration_path + ": " + e.what());
    }
  }
}

}  // namespace

std::optional<PilotOptions> parse_options(int argc, char** argv) {
  PilotOptions o;
  CLI::App app{"tello_pilot: fly a DJI Tello with the shelfcross flight software (see flight_sw/tello/README.md)"};
  CommandLine c;
  add_flight_options(app, o, c);
  add_failsafe_options(app, c);
  add_tool_options(app, o, c);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return std::nullopt;
  } catch (const CLI::ParseError& e) {
    throw UsageError(std::string(e.what()) + " (see --help)");
  }
  try {
    if (!c.pilot_file.empty()) read_pilot_file(c.pilot_file, o);
  } catch (const config::ConfigError& e) {
    throw UsageError(e.what());
  } catch (const std::exception& e) {
    throw UsageError(c.pilot_file + ": " + e.what());
  }
  apply_command_line(c, o);
  if (o.failsafes.video_land_s < o.failsafes.video_hover_s) {
    throw UsageError("--video-land must not be shorter than --video-hover");
  }
  if (o.failsafes.link_outage_s < o.failsafes.state_timeout_s) {
    throw UsageError("--link-outage must not be shorter than --state-timeout");
  }
  try {
    parse_ipv4(o.driver.drone_ip);
    parse_ipv4(o.driver.local_ip);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  o.video.drone_ip = o.driver.drone_ip;
  o.video.local_ip = o.driver.local_ip;
  parse_board_and_markers(c, o);
  load_flight_files(o);
  if (o.senses_board_m && !o.fly_calibration) throw UsageError("--senses-board is part of --fly-calibration");
  if (c.budget->count()) o.flight.timeouts.mission_s = c.mission_s;
  if (o.fly_calibration && !o.calibrate_path.empty()) {
    throw UsageError("--fly-calibration and --calibrate: one at a time (the camera's calibration never flies)");
  }
  o.driver.dry_run = o.dry_run || !o.calibrate_path.empty();  // calibrating never flies
  return o;
}

}  // namespace shelfcross::tello::pilot
