// Calibration mode of tello_pilot: the camera's intrinsics from chessboard views of the
// stream itself (960 x 720, as the flight software sees it), written in OpenCV's format.
#include <poll.h>

#include <iostream>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "flight_sw/tello/flight_log.hpp"
#include "flight_sw/tello/pilot/pilot.hpp"
#include "flight_sw/tello/sdk_driver.hpp"
#include "flight_sw/tello/video_receiver.hpp"

namespace shelfcross::tello::pilot {

int run_calibration(const PilotOptions& o, const Clock& clock, const std::atomic<int>& signals) {
  std::optional<FlightLog> log_file;
  try {
    log_file.emplace(o.log_path);
  } catch (const FlightLogError& e) {
    throw UsageError(e.what());
  }
  FlightLog& log = *log_file;
  DriverConfig dc = o.driver;
  dc.dry_run = true;  // nothing but command and streamon can leave this program
  SdkDriver driver(dc, clock);
  VideoReceiver video(o.video, clock);
  const cv::Size board(o.board_columns, o.board_rows);
  std::vector<cv::Point3f> board_points;
  for (int r = 0; r < board.height; ++r) {
    for (int c = 0; c < board.width; ++c) {
      board_points.emplace_back(static_cast<float>(c * o.square_m), static_cast<float>(r * o.square_m), 0.0f);
    }
  }
  std::vector<std::vector<cv::Point2f>> views;
  cv::Size image_size;
  TimeNs last_view_ns = -kNsPerSecond;
  log.write(clock.now_ns(), "start", {{"mode", "calibrate"}, {"board", std::to_string(board.width) + "x" + std::to_string(board.height)},
                                      {"square_m", o.square_m}});
  driver.submit("command");
  driver.submit("streamon");
  std::cout << "tello_pilot: calibrating; show the " << board.width << "x" << board.height
            << " chessboard to the camera from many angles and distances" << std::endl;
  while (static_cast<int>(views.size()) < o.calibration_views) {
    if (signals.load() > 0) {
      std::cout << "tello_pilot: calibration stopped, nothing written" << std::endl;
      return 130;
    }
    pollfd fds[2] = {{driver.command_fd(), POLLIN, 0}, {video.notify_fd(), POLLIN, 0}};
    ::poll(fds, 2, 10);
    driver.service();
    for (const DriverEvent& e : driver.take_events()) {
      if (e.kind == DriverEvent::Kind::State) continue;
      log.write(e.t_ns, event_kind_name(e.kind), {{"command", e.command}, {"reply", e.reply}});
      if (e.kind == DriverEvent::Kind::Failed) {
        std::cerr << "tello_pilot: '" << e.command << "' got no reply: is the computer on the Tello's Wi-Fi?" << std::endl;
        return 1;
      }
    }
    auto f = video.take_latest();
    if (!f) continue;
    log.write(f->handed_ns, "frame", {{"index", f->index}, {"rx_ns", f->t_ns}});
    // Views at least 0.5 s apart, so the operator moves the board between them.
    if (f->handed_ns - last_view_ns < kNsPerSecond / 2) continue;
    cv::Mat gray;
    cv::cvtColor(f->bgr, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point2f> corners;
    if (!cv::findChessboardCorners(gray, board, corners,
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK)) {
      continue;
    }
    cv::cornerSubPix(gray, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
    views.push_back(corners);
    image_size = gray.size();
    last_view_ns = f->handed_ns;
    std::cout << "  view " << views.size() << "/" << o.calibration_views << std::endl;
  }
  std::vector<std::vector<cv::Point3f>> object(views.size(), board_points);
  cv::Mat K, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  const double rms = cv::calibrateCamera(object, views, image_size, K, dist, rvecs, tvecs);
  cv::FileStorage fs(o.calibrate_path, cv::FileStorage::WRITE);
  if (!fs.isOpened()) {
    std::cerr << "tello_pilot: cannot write '" << o.calibrate_path << "'" << std::endl;
    return 1;
  }
  fs << "image_width" << image_size.width << "image_height" << image_size.height << "camera_matrix" << K
     << "distortion_coefficients" << dist << "rms_reprojection_error_px" << rms
     << "views" << static_cast<int>(views.size()) << "square_m" << o.square_m;
  fs.release();
  log.write(clock.now_ns(), "end", {{"rms_px", rms}, {"fx", K.at<double>(0, 0)}, {"fy", K.at<double>(1, 1)}});
  std::cout << "tello_pilot: wrote " << o.calibrate_path << " (RMS reprojection error " << rms << " px)" << std::endl;
  driver.submit("streamoff");
  driver.service();
  return 0;
}

}  // namespace shelfcross::tello::pilot
