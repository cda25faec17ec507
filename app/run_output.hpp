#pragma once
// Writing one run's outputs (shared by `shelfcross run` and `shelfcross replay`):
//   DIR/run.json         outcome, detail, metrics, hash, seed, drawn dispersions, inventory
//   DIR/trajectory.csv   truth and phase at cosim.trajectory_rate_hz
//   DIR/events.log       phases, commands, replies, contacts, outcome, stamped
//   DIR/video.mp4        (with --video) the camera as the flight software received it, with
//                        what it computed from each picture drawn on that picture: H.264
//                        (`avc1`) in MP4, yuv420p, at the camera's rate and size (30 fps,
//                        960 x 720 for the Tello), which browsers play.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "shelfcross/cell_index.hpp"
#include "verification/cosim/cosim.hpp"

namespace shelfcross::app {

/// Runs `setup` with a renderer of its own and writes the outputs; returns the result.
verification::RunResult run_and_write(const verification::RunSetup& setup, const std::filesystem::path& dir,
                                      bool video);

/// What the flight software showed after handling one picture, sorted by the picture each
/// annotation was computed from. The flight software's telemetry keeps a value until it is
/// computed again: while approaching, the tag list is the one of the last full-shelf analysis
/// (seconds old), the tracked box and the control errors those of the last picture in which
/// the target was measured. Drawn on the picture being shown, such values sit where the tags
/// were, not where they are. Only annotations of this picture are drawn on it; the others are
/// named, with the picture they come from, in the text.
struct FrameAnnotations {
  /// Where an annotation comes from: the picture's source index and receive time.
  struct Source {
    std::int64_t frame = -1;
    TimeNs t_ns = 0;
  };

  std::int64_t frame = 0;  ///< this picture's source index (CameraFrame::index)
  TimeNs t_ns = 0;         ///< this picture's receive time
  bool damaged = false;
  std::string phase;
  std::optional<CellIndex> target;

  // Computed from this picture (or from a picture identical to it, pixel for pixel).
  std::vector<flight_sw::TagTelemetry> tags;
  std::optional<cv::Rect2d> tracked_box_px;
  std::optional<double> e_z_m, e_psi_rad;

  // Held by the flight software from an earlier, different picture: not drawn on this one.
  std::optional<Source> stale_tags;    ///< a non-empty tag list of that picture
  std::optional<Source> stale_box;     ///< the tracked box of that picture
  std::optional<Source> stale_errors;  ///< e_z, e_psi of that picture
  double stale_e_z_m = 0.0, stale_e_psi_rad = 0.0;
};

/// Sorts each picture's telemetry into FrameAnnotations. Feed it every picture the flight
/// software handled, in order, with the telemetry right after it handled that picture (what
/// verification::FrameObserver is called with). An annotation counts as computed from the
/// picture after which its value changed; later pictures get it only if they are identical,
/// pixel for pixel, to that one (the same picture gives the same result).
class AnnotationSorter {
 public:
  FrameAnnotations sort(const CameraFrame& frame, const flight_sw::Telemetry& tm);

 private:
  template <class T>
  struct Held {
    T value{};
    bool seen = false;
    FrameAnnotations::Source source;
    cv::Mat picture;  ///< a copy of the picture it was computed from
  };
  // Returns true when `value` was computed from `frame` (see the class comment).
  template <class T, class Eq>
  static bool update(Held<T>& held, const T& value, const CameraFrame& frame, Eq equal);

  Held<std::vector<flight_sw::TagTelemetry>> tags_;
  Held<std::optional<cv::Rect2d>> box_;
  Held<std::pair<double, double>> errors_;
};

/// Draws `a` on `img` (the picture it was sorted for): tags with their grid row and column,
/// the tracked box, and the text lines (time, frame, phase, errors, what is held from earlier
/// pictures).
void draw_annotations(cv::Mat& img, const FrameAnnotations& a);

/// The replay video: H.264 in MP4 through OpenCV's FFmpeg backend (libx264). Pictures are
/// placed by their source index, so the video keeps the camera's timeline: a picture that never
/// arrived is filled with the last one written, marked as not received.
class ReplayVideo {
 public:
  /// Throws std::runtime_error when the file cannot be opened for H.264 writing.
  ReplayVideo(const std::filesystem::path& path, double fps, cv::Size size);
  /// One received picture (already annotated), with its source index.
  void write(const cv::Mat& annotated, std::int64_t frame);
  std::int64_t frames_written() const { return written_; }

 private:
  cv::VideoWriter writer_;
  cv::Size size_;
  std::optional<std::int64_t> last_frame_;
  cv::Mat last_;
  std::int64_t written_ = 0;
};

}  // namespace shelfcross::app
