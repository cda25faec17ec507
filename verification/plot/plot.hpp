#pragma once
// Charts for campaign reports, drawn with OpenCV and written as PNG: line and point series,
// rectangles (shelves, cells in top and side views), horizontal bands (settling bands),
// histograms. Axes get "nice" ticks (1, 2, 5 x 10^k); equal aspect for geometric views.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace shelfcross::verification {

/// The shelves' colour in every plot that draws them (BGR).
inline const cv::Scalar kShelfBgr(120, 80, 40);

class Chart {
 public:
  Chart(std::string title, std::string x_label, std::string y_label, int width_px = 960,
        int height_px = 640);

  /// A polyline; NaN values break the line.
  void add_line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
                int thickness = 1, const std::string& label = "");
  void add_points(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
                  int radius_px = 3, const std::string& label = "");
  void add_rect(double x0, double y0, double x1, double y1, const cv::Scalar& bgr, bool filled,
                const std::string& label = "");
  void add_hline(double y, const cv::Scalar& bgr, const std::string& label = "");
  /// Bars from `x_edges` (n+1 values) and `heights` (n values).
  void add_bars(const std::vector<double>& x_edges, const std::vector<double>& heights, const cv::Scalar& bgr);

  void set_equal_aspect(bool equal) { equal_aspect_ = equal; }
  void set_x_limits(double lo, double hi);
  void set_y_limits(double lo, double hi);

  cv::Mat draw() const;
  /// Writes the PNG; throws std::runtime_error if it cannot.
  void save_png(const std::string& path) const;

 private:
  struct Item {
    enum class Kind { line, points, rect, filled_rect, hline, bars } kind;
    std::vector<double> x, y;
    cv::Scalar colour;
    int size;
    std::string label;
  };
  std::string title_, x_label_, y_label_;
  int width_px_, height_px_;
  bool equal_aspect_ = false;
  bool x_fixed_ = false, y_fixed_ = false;
  double x_lo_ = 0, x_hi_ = 1, y_lo_ = 0, y_hi_ = 1;
  std::vector<Item> items_;
};

/// A histogram chart of `values` with `bins` equal bins over their range.
Chart histogram_chart(const std::vector<double>& values, int bins, const std::string& title,
                      const std::string& x_label);

/// Ticks at 1, 2 or 5 x 10^k covering [lo, hi] with about `target` intervals.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

}  // namespace shelfcross::verification
