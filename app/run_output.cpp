#include "run_output.hpp"

#include <algorithm>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "command_registry.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/cosim/run_metrics_json.hpp"

namespace shelfcross::app {
namespace {

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty() || a.size() != b.size() || a.type() != b.type()) return false;
  return cv::norm(a, b, cv::NORM_INF) == 0.0;
}

bool same_tags(const std::vector<flight_sw::TagTelemetry>& a, const std::vector<flight_sw::TagTelemetry>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& x, const auto& y) {
    return x.centre_px == y.centre_px && x.area_px == y.area_px && x.tag_row == y.tag_row &&
           x.tag_column == y.tag_column;
  });
}

std::string from_text(const FrameAnnotations::Source& s, TimeNs now_ns) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << "frame #" << s.frame << ", " << ns_to_seconds(now_ns - s.t_ns)
     << " s earlier";
  return os.str();
}

void put_line(cv::Mat& img, const std::string& text, int row, const cv::Scalar& colour) {
  const cv::Point at(12, 28 + 26 * row);
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 4, cv::LINE_AA);
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.6, colour, 1, cv::LINE_AA);
}

}  // namespace

template <class T, class Eq>
bool AnnotationSorter::update(Held<T>& held, const T& value, const CameraFrame& frame, Eq equal) {
  if (!held.seen || !equal(held.value, value)) {
    held.value = value;
    held.seen = true;
    held.source = {frame.index, frame.t_ns};
    frame.bgr.copyTo(held.picture);
    return true;
  }
  return held.source.frame == frame.index || same_pixels(held.picture, frame.bgr);
}

FrameAnnotations AnnotationSorter::sort(const CameraFrame& frame, const flight_sw::Telemetry& tm) {
  FrameAnnotations a;
  a.frame = frame.index;
  a.t_ns = frame.t_ns;
  a.damaged = frame.damaged || frame.damage_events > 0;
  a.phase = flight_sw::phase_name(tm.phase);
  a.target = tm.tracking.target;
  if (update(tags_, tm.view.tags, frame, same_tags)) {
    a.tags = tm.view.tags;
  } else if (!tm.view.tags.empty()) {
    a.stale_tags = tags_.source;
  }
  if (update(box_, tm.tracking.tracked_box_px, frame, std::equal_to<>())) {
    a.tracked_box_px = tm.tracking.tracked_box_px;
  } else if (tm.tracking.tracked_box_px) {
    a.stale_box = box_.source;
  }
  // e_z and e_psi are computed together, from the target's corner tags (approach only).
  const std::pair<double, double> errors(tm.control.e_z_m, tm.control.e_psi_rad);
  if (update(errors_, errors, frame, std::equal_to<>())) {
    if (errors != std::pair<double, double>(0.0, 0.0)) {
      a.e_z_m = tm.control.e_z_m;
      a.e_psi_rad = tm.control.e_psi_rad;
    }
  } else if (errors != std::pair<double, double>(0.0, 0.0)) {
    a.stale_errors = errors_.source;
    a.stale_e_z_m = tm.control.e_z_m;
    a.stale_e_psi_rad = tm.control.e_psi_rad;
  }
  return a;
}

void draw_annotations(cv::Mat& img, const FrameAnnotations& a) {
  for (const auto& tag : a.tags) {
    const cv::Scalar colour = tag.tag_row >= 0 ? cv::Scalar(0, 255, 255) : cv::Scalar(0, 0, 255);
    cv::circle(img, tag.centre_px, 6, colour, 2, cv::LINE_AA);
    if (tag.tag_row >= 0) {
      cv::putText(img, std::to_string(tag.tag_row) + "," + std::to_string(tag.tag_column),
                  tag.centre_px + cv::Point2d(8, -8), cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1, cv::LINE_AA);
    }
  }
  if (a.tracked_box_px) cv::rectangle(img, *a.tracked_box_px, cv::Scalar(255, 0, 255), 2, cv::LINE_AA);

  const cv::Scalar white(255, 255, 255), grey(170, 170, 170);
  std::ostringstream head;
  head << std::fixed << std::setprecision(2) << ns_to_seconds(a.t_ns) << " s  frame #" << a.frame << "  " << a.phase;
  if (a.target) head << "  target L" << a.target->level << " C" << a.target->column;
  if (a.damaged) head << "  DAMAGED";
  put_line(img, head.str(), 0, white);
  int row = 1;
  std::ostringstream errors;
  errors << std::fixed << std::setprecision(3);
  if (a.e_z_m) {
    errors << "e_z " << *a.e_z_m << " m  e_psi " << *a.e_psi_rad << " rad";
    put_line(img, errors.str(), row++, white);
  } else if (a.stale_errors) {
    errors << "e_z " << a.stale_e_z_m << " m  e_psi " << a.stale_e_psi_rad << " rad  ("
           << from_text(*a.stale_errors, a.t_ns) << ")";
    put_line(img, errors.str(), row++, grey);
  }
  if (a.stale_tags) put_line(img, "tags not drawn: from " + from_text(*a.stale_tags, a.t_ns), row++, grey);
  if (a.stale_box) put_line(img, "box not drawn: from " + from_text(*a.stale_box, a.t_ns), row++, grey);
}

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
  AnnotationSorter sorter;
  cv::Mat annotated;
  const verification::FrameObserver observer = [&](const CameraFrame& frame, const flight_sw::FlightSoftware& fsw) {
    const FrameAnnotations a = sorter.sort(frame, fsw.telemetry());
    frame.bgr.copyTo(annotated);
    draw_annotations(annotated, a);
    writer->write(annotated, frame.index);
  };
  const verification::RunResult result =
      verification::run_cosimulation(setup, renderer, video ? observer : verification::FrameObserver{});

  json run{{"scenario", sc.name},
           {"seed", setup.seed},
           {"drawn", setup.drawn},
           {"outcome", verification::outcome_name(result.outcome)},
           {"detail", result.detail},
           {"metrics", json(result.metrics)},
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
