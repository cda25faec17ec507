// shelfcross render --scenario FILE [--pose x,y,z,roll,pitch,yaw] --out frame.png: one camera
// frame, so a person can look at the scene.
#include <iostream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "command_registry.hpp"
#include "render/ground_truth.hpp"
#include "render/renderer.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::app {
namespace {

struct RenderCommandOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::string pose;
  std::string out = "frame.png";
};

const CommandRegistration kRender{
    "render", "Render one camera frame of a scenario to a PNG", [](CLI::App& sub) {
      auto o = std::make_shared<RenderCommandOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--pose", o->pose,
                     "body pose x,y,z,roll,pitch,yaw (m, rad; world frame, ZYX angles); default: the start "
                     "pose lifted to the autopilot's take-off height");
      sub.add_option("--out", o->out, "PNG to write")->capture_default_str();
      return [o]() -> int {
        const verification::Scenario s = verification::load_scenario(o->scenario);
        Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
        if (o->pose.empty()) {
          X_WB.linear() = Eigen::AngleAxisd(s.start.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
          X_WB.translation() = s.start.p_WB_m + Eigen::Vector3d(0, 0, s.autopilot.takeoff_height_m);
        } else {
          std::vector<double> v;
          std::stringstream in(o->pose);
          std::string item;
          while (std::getline(in, item, ',')) {
            try {
              size_t used = 0;
              v.push_back(std::stod(item, &used));
              if (used != item.size()) throw std::invalid_argument(item);
            } catch (const std::exception&) {
              throw UsageError("--pose: '" + item + "' is not a number");
            }
          }
          if (v.size() != 6) throw UsageError("--pose needs six numbers: x,y,z,roll,pitch,yaw");
          X_WB.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                              .toRotationMatrix();
          X_WB.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
        }
        render::Renderer renderer(s.warehouse, s.camera);
        const cv::Mat frame = renderer.render(render::camera_pose_W(X_WB, s.camera_mount));
        if (!cv::imwrite(o->out, frame)) throw UsageError("cannot write " + o->out);
        std::cout << "wrote " << o->out << " (" << frame.cols << " x " << frame.rows << ", "
                  << renderer.backend_description() << ")\n";
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
