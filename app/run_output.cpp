#include "run_output.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "command_registry.hpp"
#include "verification/campaign.hpp"

namespace shelfcross::app {
namespace {

// The flight software's view of a frame, drawn for people: tags with their grid labels, the
// tracked box, the phase and the control errors.
void annotate(cv::Mat& img, const flight_sw::FlightSoftware& fsw, TimeNs t_ns) {
  const flight_sw::Telemetry& tm = fsw.telemetry();
  for (const auto& tag : tm.tags) {
    const cv::Scalar colour = tag.tag_row >= 0 ? cv::Scalar(0, 255, 255) : cv::Scalar(0, 0, 255);
    cv::circle(img, tag.centre_px, 6, colour, 2, cv::LINE_AA);
    if (tag.tag_row >= 0) {
      cv::putText(img, std::to_string(tag.tag_row) + "," + std::to_string(tag.tag_column), tag.centre_px + cv::Point2d(8, -8),
                  cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1, cv::LINE_AA);
    }
  }
  if (tm.tracked_box_px) cv::rectangle(img, *tm.tracked_box_px, cv::Scalar(255, 0, 255), 2, cv::LINE_AA);
  std::ostringstream line;
  line << std::fixed << std::setprecision(2) << ns_to_seconds(t_ns) << " s  " << flight_sw::phase_name(tm.phase)
       << "  e_z " << tm.e_z_m << " m  e_psi " << tm.e_psi_rad << " rad";
  if (tm.target) line << "  target L" << tm.target->level << " C" << tm.target->column;
  cv::putText(img, line.str(), {12, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(0, 0, 0), 4, cv::LINE_AA);
  cv::putText(img, line.str(), {12, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

}  // namespace

ReplayVideo::ReplayVideo(const std::filesystem::path& path, double fps, cv::Size size) : size_(size) {
  // fourcc avc1: H.264 with the MP4 sample entry browsers expect; OpenCV's FFmpeg backend
  // encodes it with libx264 in yuv420p.
  writer_.open(path.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('a', 'v', 'c', '1'), fps, size);
  if (!writer_.isOpened()) {
    throw std::runtime_error("cannot open " + path.string() +
                             " for H.264 writing (OpenCV videoio, FFmpeg backend with libx264)");
  }
}

void ReplayVideo::write(const cv::Mat& annotated, std::int64_t frame) {
  if (annotated.size() != size_ || annotated.type() != CV_8UC3) {
    throw std::invalid_argument("replay video: picture of the wrong size or type");
  }
  // Pictures that never arrived: the last picture again, marked, so the video keeps time.
  if (last_frame_ && !last_.empty()) {
    for (std::int64_t missing = *last_frame_ + 1; missing < frame; ++missing) {
      cv::Mat copy = last_.clone();
      cv::putText(copy, "frame #" + std::to_string(missing) + " not received", {12, size_.height - 16},
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
      writer_.write(copy);
      ++written_;
    }
  }
  writer_.write(annotated);
  ++written_;
  annotated.copyTo(last_);
  last_frame_ = last_frame_ ? std::max(*last_frame_, frame) : frame;
}

verification::RunResult run_and_write(const verification::RunSetup& setup, const std::filesystem::path& dir, bool video) {
  using nlohmann::json;
  const verification::Scenario& sc = *setup.scenario;
  std::filesystem::create_directories(dir);
  render::Renderer renderer(sc.warehouse, sc.camera, verification::render_options_for(sc));
  std::unique_ptr<ReplayVideo> writer;
  if (video) {
    writer = std::make_unique<ReplayVideo>(dir / "video.mp4", sc.frame_rate_hz,
                                           cv::Size(sc.camera.width_px, sc.camera.height_px));
  }
  cv::Mat annotated;
  const verification::FrameObserver observer = [&](const CameraFrame& frame, const flight_sw::FlightSoftware& fsw) {
    frame.bgr.copyTo(annotated);
    annotate(annotated, fsw, frame.t_ns);
    writer->write(annotated, frame.index);
  };
  const verification::RunResult result =
      verification::run_cosimulation(setup, renderer, video ? observer : verification::FrameObserver{});

  json run{{"scenario", sc.name},
           {"seed", setup.seed},
           {"drawn", setup.drawn},
           {"outcome", verification::outcome_name(result.outcome)},
           {"detail", result.detail},
           {"metrics", json::parse(verification::run_metrics_json(result.metrics))},
           {"run_hash", result.run_hash},
           {"inventory", json::parse(result.inventory_json)},
           {"renderer", renderer.backend_description()}};
  std::ofstream(dir / "run.json") << run.dump(2) << "\n";
  std::ofstream csv(dir / "trajectory.csv");
  csv << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,roll_rad,pitch_rad,yaw_rad,phase\n" << std::setprecision(9);
  for (const auto& s : result.trajectory) {
    csv << s.t_s << ',' << s.p_WB_m.x() << ',' << s.p_WB_m.y() << ',' << s.p_WB_m.z() << ',' << s.v_WB_W_mps.x() << ','
        << s.v_WB_W_mps.y() << ',' << s.v_WB_W_mps.z() << ',' << s.roll_rad << ',' << s.pitch_rad << ',' << s.yaw_rad
        << ',' << s.phase << '\n';
  }
  std::ofstream events(dir / "events.log");
  for (const auto& e : result.events) events << e << '\n';
  return result;
}

}  // namespace shelfcross::app
