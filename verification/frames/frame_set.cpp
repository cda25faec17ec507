#include "verification/frames/frame_set.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flight_sw/navigation/navigation.hpp"
#include "render/ground_truth.hpp"
#include "render/noise.hpp"
#include "render/renderer.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/rotation.hpp"
#include "verification/cosim/cosim.hpp"

namespace shelfcross::frames {

const std::vector<Condition>& frame_conditions() {
  static const std::vector<Condition> c{
      {"nominal", 1.0, false}, {"dim", 0.5, false}, {"bright", 1.6, false}, {"behind", 1.0, true}};
  return c;
}

verification::Scenario condition_scenario(const verification::Scenario& base, const Condition& c) {
  verification::Scenario s = base;
  s.warehouse.lighting.ambient *= c.light_scale;
  s.warehouse.lighting.directional *= c.light_scale;
  if (c.shelf_behind && !s.warehouse.shelves.empty()) {
    const ShelfSpec& front = s.warehouse.shelves.front();
    ShelfSpec behind = front;
    behind.name = front.name + "_behind";
    behind.origin_W_m = shelf_pose_W(front) * Eigen::Vector3d(1.2, 0.0, 0.0);
    behind.boxes.clear();
    std::vector<int> used;
    for (const ShelfSpec& sh : s.warehouse.shelves) {
      for (const BoxPlacement& b : sh.boxes) used.push_back(b.marker_id);
    }
    int next_id = 0;
    for (int level = 1; level <= static_cast<int>(front.row_pitch_m.size()); ++level) {
      for (int column = 1; column <= static_cast<int>(front.column_pitch_m.size()); ++column) {
        const bool taken = std::any_of(front.boxes.begin(), front.boxes.end(), [&](const BoxPlacement& b) {
          return b.level == level && b.column == column;
        });
        if (taken) continue;
        while (std::find(used.begin(), used.end(), next_id) != used.end()) ++next_id;
        behind.boxes.push_back({level, column, next_id});
        used.push_back(next_id);
      }
    }
    s.warehouse.shelves.push_back(behind);
  }
  return s;
}

std::string scenario_hash(const verification::Scenario& s) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char ch : verification::write_scenario(s)) h = (h ^ ch) * 0x100000001b3ull;
  std::ostringstream os;
  os << std::hex << h;
  return os.str();
}

namespace {

Eigen::Isometry3d body_pose(const Eigen::Vector3d& p_WB_m, double yaw_rad) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = p_WB_m;
  return X;
}

/// Grid frame G (flight_sw/navigation/navigation.hpp) in shelf 0's frame S: G's origin is the grid
/// centre on the front bars' centre plane, axes as S.
Eigen::Vector3d grid_origin_S(const ShelfSpec& shelf) {
  const double top = beam_z_S_m(shelf, static_cast<int>(shelf.row_pitch_m.size()));
  return {0.0, 0.0, 0.5 * (shelf.base_height_m + top)};
}

}  // namespace

double range_to_tags_m(const verification::Scenario& sc, const flight_sw::FlightConfig& config,
                       const Eigen::Vector3d& p_WB_m, double yaw_rad) {
  const Eigen::Isometry3d X_WS = shelf_pose_W(sc.warehouse.shelves.front());
  const Eigen::Vector3d p_WC = body_pose(p_WB_m, yaw_rad) * sc.camera_mount.p_BC_B_m;
  return -(X_WS.inverse() * p_WC).x() - config.shelf.tag_offset_m;
}

CellIndex expected_target(const verification::Scenario& sc, const flight_sw::FlightConfig& config,
                          const Eigen::Isometry3d& X_WC) {
  const ShelfSpec& shelf = sc.warehouse.shelves.front();
  const render::GroundTruthProjector gt(sc.warehouse, sc.camera);
  const Eigen::Isometry3d X_WS = shelf_pose_W(shelf);
  std::optional<CellIndex> best;
  double best_d = 0.0;
  for (int level = 1; level <= config.shelf.levels(); ++level) {
    for (int column = 1; column <= config.shelf.columns(); ++column) {
      if (std::any_of(shelf.boxes.begin(), shelf.boxes.end(),
                      [&](const BoxPlacement& b) { return b.level == level && b.column == column; })) {
        continue;
      }
      const Eigen::Vector2d opening = flight_sw::cell_opening_m(config.shelf, {level, column});
      const Eigen::Vector3d& size = config.mission.vehicle_size_m;
      if (opening.x() - size.y() - 2.0 * config.mission.crossing_margin_m <= 0.0 ||
          opening.y() - size.z() - 2.0 * config.mission.crossing_margin_m <= 0.0) {
        continue;
      }
      cv::Point2d c(0, 0);
      bool all = true;
      for (int i : {column - 1, column}) {
        for (int j : {level - 1, level}) {
          const Eigen::Vector3d p_S(-config.shelf.tag_offset_m, post_y_S_m(shelf, i), beam_z_S_m(shelf, j));
          const auto px = gt.project(X_WS * p_S, X_WC);
          if (!px) all = false;
          else c += 0.25 * *px;
        }
      }
      if (!all) continue;
      const double d = std::hypot(c.x - sc.camera.cx_px, c.y - sc.camera.cy_px);
      if (!best || d < best_d) {
        best = CellIndex{level, column};
        best_d = d;
      }
    }
  }
  if (!best) throw std::runtime_error("frame set: the scenario's shelf 0 has no crossable empty cell");
  return *best;
}

std::vector<FrameSpec> frame_specs(const verification::Scenario& sc) {
  if (sc.warehouse.shelves.empty()) throw std::runtime_error("frame set: the scenario has no shelf");
  const flight_sw::FlightConfig config = verification::flight_config_for(sc, sc.camera);
  const ShelfSpec& shelf = sc.warehouse.shelves.front();
  const Eigen::Isometry3d X_WS = shelf_pose_W(shelf);
  const Eigen::Vector3d g_S = grid_origin_S(shelf);
  const Eigen::Vector3d vp_S =
      g_S + flight_sw::optimal_viewpoint_G(config.shelf, config.camera, config.mount, config.mission.viewpoint.viewpoint_margin);
  const auto camera_at = [&](const Eigen::Vector3d& p_S, double yaw_S) {
    return render::camera_pose_W(body_pose(X_WS * p_S, shelf.yaw_rad + yaw_S), sc.camera_mount);
  };
  const CellIndex target = expected_target(sc, config, camera_at(vp_S, 0.0));
  const Eigen::Vector3d cell_S = cell_centre_S_m(shelf, target.level, target.column);
  // Last pose: on the cell normal, camera kApproachEndRange_m in front of the tag plane.
  const Eigen::Vector3d end_S(-(kApproachEndRange_m + config.shelf.tag_offset_m) - sc.camera_mount.p_BC_B_m.x(),
                              cell_S.y() - sc.camera_mount.p_BC_B_m.y(), cell_S.z() - sc.camera_mount.p_BC_B_m.z());

  std::vector<FrameSpec> specs;
  std::uint64_t counter = 0;
  const auto add = [&](std::string name, std::string group, std::string condition, int step,
                       const Eigen::Vector3d& p_S, double yaw_S) {
    FrameSpec f;
    f.name = std::move(name);
    f.group = std::move(group);
    f.condition = std::move(condition);
    f.step = step;
    f.p_WB_m = X_WS * p_S;
    f.yaw_rad = wrap_pi(shelf.yaw_rad + yaw_S);
    f.range_m = range_to_tags_m(sc, config, f.p_WB_m, f.yaw_rad);
    f.noise_seed = mix64(0xBE7C4F2A3E5D0001ull + counter++);
    specs.push_back(std::move(f));
  };
  char name[64];
  for (const Condition& c : frame_conditions()) {
    for (int k = 0; k < kViewpointFrames; ++k) {
      // Hover jitter: a few millimetres and milliradians, fixed.
      const double a = 0.9 * k;
      const Eigen::Vector3d jitter(0.004 * std::sin(a), 0.005 * std::cos(1.3 * a), 0.003 * std::sin(2.1 * a));
      std::snprintf(name, sizeof name, "%s_%03d", c.name, k);
      add(name, "viewpoint", c.name, k, vp_S + jitter, 0.004 * std::sin(1.7 * a));
    }
    double yaw_S = 0.0;
    for (int k = 0; k < kApproachFrames; ++k) {
      const double s = static_cast<double>(k + 1) / kApproachFrames;
      const Eigen::Vector3d p_S = (1.0 - s) * vp_S + s * end_S;
      const Eigen::Vector3d p_C_S = p_S + sc.camera_mount.p_BC_B_m;  // heading ~0: close enough to aim
      // Heading toward the cell centre, turning at most kApproachYawRate_radps.
      const double aim = std::atan2(cell_S.y() - p_C_S.y(), cell_S.x() - p_C_S.x());
      const double max_turn = kApproachYawRate_radps / static_cast<double>(kFrameRateHz);
      yaw_S += std::clamp(aim - yaw_S, -max_turn, max_turn);
      const double range = range_to_tags_m(sc, config, X_WS * p_S, shelf.yaw_rad + yaw_S);
      std::snprintf(name, sizeof name, "%s_%03d", c.name, kViewpointFrames + k);
      add(name, range < kCloseRange_m ? "close" : "approach", c.name, kViewpointFrames + k, p_S, yaw_S);
    }
  }
  // FindShelf stills (nominal): at the take-off height, farther away, turned, and a bare wall.
  const double z = sc.autopilot.takeoff_height_m + (sc.start.landed ? 0.5 * sc.vehicle.size_m.z() : 0.0);
  struct Still {
    const char* name;
    double range_m, lateral_m, yaw_rad;
  };
  for (const Still& st : {Still{"far_3m", 3.0, 0.0, 0.0}, Still{"far_4m", 4.2, 0.3, -0.05},
                          Still{"far_turned", 3.0, 0.0, 0.45}, Still{"far_wall", 3.0, 0.0, 1.4}}) {
    const Eigen::Vector3d p_S(-(st.range_m + config.shelf.tag_offset_m) - sc.camera_mount.p_BC_B_m.x(), st.lateral_m, z);
    add(st.name, "far", "nominal", -1, p_S, st.yaw_rad);
  }
  return specs;
}

std::string manifest_header(const verification::Scenario& sc) {
  std::ostringstream os;
  os << "# shelfcross bench frames version " << kFrameSetVersion << " scenario " << sc.name << " hash "
     << scenario_hash(sc) << " noise_stddev " << sc.cosim.render_noise_stddev;
  return os.str();
}

std::optional<std::string> frame_set_stale(const std::filesystem::path& dir, const verification::Scenario& sc) {
  std::ifstream in(dir / "manifest.csv");
  if (!in) return "no " + (dir / "manifest.csv").string();
  std::string first;
  std::getline(in, first);
  if (first != manifest_header(sc)) return "manifest header '" + first + "' differs from '" + manifest_header(sc) + "'";
  return std::nullopt;
}

int generate_frame_set(const verification::Scenario& sc, const std::filesystem::path& dir,
                       const std::string& only_condition) {
  std::filesystem::create_directories(dir);
  const std::vector<FrameSpec> specs = frame_specs(sc);
  std::ofstream manifest(dir / "manifest.csv.tmp");
  manifest << manifest_header(sc) << "\n";
  manifest << "name,group,condition,step,x_W_m,y_W_m,z_W_m,yaw_rad,range_m,noise_seed\n";
  manifest.precision(17);
  std::optional<render::Renderer> renderer;
  std::string current;
  int written = 0;
  for (const FrameSpec& f : specs) {
    if (!only_condition.empty() && f.condition != only_condition) continue;
    if (f.condition != current) {
      const auto& cs = frame_conditions();
      const auto c = std::find_if(cs.begin(), cs.end(), [&](const Condition& x) { return f.condition == x.name; });
      const verification::Scenario csc = condition_scenario(sc, *c);
      if (!renderer) renderer.emplace(csc.warehouse, csc.camera);  // noise added on load
      else renderer->set_warehouse(csc.warehouse);
      current = f.condition;
    }
    const cv::Mat bgr = renderer->render(render::camera_pose_W(body_pose(f.p_WB_m, f.yaw_rad), sc.camera_mount));
    const std::string file = (dir / (f.name + ".png")).string();
    if (!cv::imwrite(file, bgr, {cv::IMWRITE_PNG_COMPRESSION, 3})) throw std::runtime_error("cannot write " + file);
    manifest << f.name << ',' << f.group << ',' << f.condition << ',' << f.step << ',' << f.p_WB_m.x() << ','
             << f.p_WB_m.y() << ',' << f.p_WB_m.z() << ',' << f.yaw_rad << ',' << f.range_m << ',' << f.noise_seed
             << "\n";
    ++written;
  }
  manifest.close();
  std::filesystem::rename(dir / "manifest.csv.tmp", dir / "manifest.csv");
  return written;
}

FrameSet load_frame_set(const std::filesystem::path& dir, const verification::Scenario& sc) {
  if (auto why = frame_set_stale(dir, sc)) throw std::runtime_error("frame set: " + *why);
  std::ifstream in(dir / "manifest.csv");
  std::string line;
  std::getline(in, line);
  std::getline(in, line);  // column names
  FrameSet set;
  set.source = dir.string();
  const render::SensorNoise noise(sc.camera.height_px, sc.camera.width_px, 3, sc.cosim.render_noise_stddev);
  int line_no = 2;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    const std::string where = (dir / "manifest.csv").string() + ":" + std::to_string(line_no) + ": ";
    if (cells.size() != 10) throw std::runtime_error(where + "expected 10 columns");
    Frame f;
    try {
      f.spec.name = cells[0];
      f.spec.group = cells[1];
      f.spec.condition = cells[2];
      f.spec.step = std::stoi(cells[3]);
      f.spec.p_WB_m = {std::stod(cells[4]), std::stod(cells[5]), std::stod(cells[6])};
      f.spec.yaw_rad = std::stod(cells[7]);
      f.spec.range_m = std::stod(cells[8]);
      f.spec.noise_seed = std::stoull(cells[9]);
    } catch (const std::exception&) {
      throw std::runtime_error(where + "bad number");
    }
    const std::string file = (dir / (f.spec.name + ".png")).string();
    f.bgr = cv::imread(file, cv::IMREAD_COLOR);
    if (f.bgr.empty()) throw std::runtime_error("cannot read " + file);
    if (sc.cosim.render_noise_stddev > 0.0) noise.apply(f.bgr, f.spec.noise_seed);
    set.frames.push_back(std::move(f));
  }
  return set;
}

FrameSet load_image_folder(const std::filesystem::path& dir, int width_px, int height_px) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  FrameSet set;
  set.source = dir.string();
  int step = 0;
  for (const auto& p : files) {
    Frame f;
    f.spec.name = p.stem().string();
    f.spec.group = "recorded";
    f.spec.condition = "recorded";
    f.spec.step = step++;
    f.bgr = cv::imread(p.string(), cv::IMREAD_COLOR);
    if (f.bgr.empty()) throw std::runtime_error("cannot read " + p.string());
    if (f.bgr.cols != width_px || f.bgr.rows != height_px) {
      cv::resize(f.bgr, f.bgr, cv::Size(width_px, height_px), 0, 0, cv::INTER_AREA);
    }
    set.frames.push_back(std::move(f));
  }
  if (set.frames.empty()) throw std::runtime_error("no images in " + dir.string());
  return set;
}

}  // namespace shelfcross::frames
