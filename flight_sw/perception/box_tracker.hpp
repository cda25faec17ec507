#pragma once
// The fast pipeline's tracker of the target's box between its measurements.

#include <deque>
#include <optional>

#include <opencv2/core.hpp>

#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

/// The fast pipeline's tracker of the target's box (the box of its four corner tags):
/// between measurements the box moves at the image velocity, and grows at the rate, fitted by
/// least squares to its measurements of the last kRateWindow_s (per second of input stamps),
/// from the last measurement on; after `coast_s` without one it stays where it was last
/// measured. The stamps are receive times: over a lossy or jittery link pictures arrive in
/// bursts a millisecond apart, and a two-point difference over such a gap turns a few pixels
/// of measurement noise into hundreds of pixels a second that throw the search window off the
/// tags. Measurements spanning less than kRateMinSpan_s give no rate (the box stays).
class BoxTracker {
 public:
  void init(const cv::Rect2d& box, TimeNs t_ns);
  void correct(const cv::Rect2d& box, TimeNs t_ns);
  std::optional<cv::Rect2d> predict(TimeNs t_ns) const;
  static constexpr double kCoast_s = 0.5;
  static constexpr double kRateWindow_s = 0.2;   ///< six frame periods at 30 frames/s
  static constexpr double kRateMinSpan_s = 0.05;  ///< a frame and a half

 private:
  struct Measured {
    TimeNs t_ns;
    cv::Vec4d v;  ///< centre x, centre y, width, height
  };
  std::deque<Measured> recent_;  ///< the window's measurements, oldest first
  cv::Vec4d rate_per_s_{0, 0, 0, 0};  ///< d/dt of (centre x, centre y, width, height)
};

}  // namespace shelfcross::flight_sw
