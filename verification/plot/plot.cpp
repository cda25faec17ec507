#include "verification/plot/plot.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace shelfcross::verification {
namespace {

constexpr int kLeft = 100, kRight = 30, kTop = 50, kBottom = 70;
const cv::Scalar kInk(30, 30, 30), kGrid(225, 225, 225), kWhite(255, 255, 255);

std::string tick_text(double v, double step) {
  std::ostringstream s;
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << (std::abs(v) < step * 1e-6 ? 0.0 : v);
  return s.str();
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) ticks.push_back(t);
  return ticks;
}

Chart::Chart(std::string title, std::string x_label, std::string y_label, int width_px, int height_px)
    : title_(std::move(title)), x_label_(std::move(x_label)), y_label_(std::move(y_label)),
      width_px_(width_px), height_px_(height_px) {}

void Chart::add_line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
                     int thickness, const std::string& label) {
  items_.push_back({Item::Kind::line, x, y, bgr, thickness, label});
}
void Chart::add_points(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
                       int radius_px, const std::string& label) {
  items_.push_back({Item::Kind::points, x, y, bgr, radius_px, label});
}
void Chart::add_rect(double x0, double y0, double x1, double y1, const cv::Scalar& bgr, bool filled,
                     const std::string& label) {
  items_.push_back({filled ? Item::Kind::filled_rect : Item::Kind::rect, {x0, x1}, {y0, y1}, bgr, 1, label});
}
void Chart::add_hline(double y, const cv::Scalar& bgr, const std::string& label) {
  items_.push_back({Item::Kind::hline, {}, {y}, bgr, 1, label});
}
void Chart::add_bars(const std::vector<double>& x_edges, const std::vector<double>& heights, const cv::Scalar& bgr) {
  items_.push_back({Item::Kind::bars, x_edges, heights, bgr, 1, ""});
}
void Chart::set_x_limits(double lo, double hi) { x_fixed_ = true; x_lo_ = lo; x_hi_ = hi; }
void Chart::set_y_limits(double lo, double hi) { y_fixed_ = true; y_lo_ = lo; y_hi_ = hi; }

cv::Mat Chart::draw() const {
  // Data limits over everything drawn, unless fixed.
  double xl = std::numeric_limits<double>::infinity(), xh = -xl, yl = xl, yh = -xl;
  for (const Item& it : items_) {
    for (double v : it.x) if (std::isfinite(v)) { xl = std::min(xl, v); xh = std::max(xh, v); }
    for (double v : it.y) if (std::isfinite(v)) { yl = std::min(yl, v); yh = std::max(yh, v); }
    if (it.kind == Item::Kind::bars) yl = std::min(yl, 0.0);
  }
  if (!std::isfinite(xl)) { xl = 0; xh = 1; }
  if (!std::isfinite(yl)) { yl = 0; yh = 1; }
  if (xh - xl < 1e-12) { xl -= 0.5; xh += 0.5; }
  if (yh - yl < 1e-12) { yl -= 0.5; yh += 0.5; }
  const double xpad = 0.03 * (xh - xl), ypad = 0.05 * (yh - yl);
  double x_lo = x_fixed_ ? x_lo_ : xl - xpad, x_hi = x_fixed_ ? x_hi_ : xh + xpad;
  double y_lo = y_fixed_ ? y_lo_ : yl - ypad, y_hi = y_fixed_ ? y_hi_ : yh + ypad;
  const int plot_w = width_px_ - kLeft - kRight, plot_h = height_px_ - kTop - kBottom;
  if (equal_aspect_) {
    // Same metres per pixel on both axes: widen the tighter axis about its centre.
    const double sx = (x_hi - x_lo) / plot_w, sy = (y_hi - y_lo) / plot_h;
    if (sx > sy) {
      const double c = 0.5 * (y_lo + y_hi), half = 0.5 * sx * plot_h;
      y_lo = c - half; y_hi = c + half;
    } else {
      const double c = 0.5 * (x_lo + x_hi), half = 0.5 * sy * plot_w;
      x_lo = c - half; x_hi = c + half;
    }
  }
  const auto px = [&](double x, double y) {
    return cv::Point(kLeft + static_cast<int>(std::lround((x - x_lo) / (x_hi - x_lo) * plot_w)),
                     kTop + plot_h - static_cast<int>(std::lround((y - y_lo) / (y_hi - y_lo) * plot_h)));
  };

  cv::Mat img(height_px_, width_px_, CV_8UC3, kWhite);
  const auto xticks = nice_ticks(x_lo, x_hi), yticks = nice_ticks(y_lo, y_hi);
  const double xstep = xticks.size() > 1 ? xticks[1] - xticks[0] : 1.0;
  const double ystep = yticks.size() > 1 ? yticks[1] - yticks[0] : 1.0;
  for (double t : xticks) {
    const cv::Point p = px(t, y_lo);
    cv::line(img, {p.x, kTop}, {p.x, kTop + plot_h}, kGrid);
    cv::putText(img, tick_text(t, xstep), {p.x - 15, kTop + plot_h + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kInk);
  }
  for (double t : yticks) {
    const cv::Point p = px(x_lo, t);
    cv::line(img, {kLeft, p.y}, {kLeft + plot_w, p.y}, kGrid);
    // Right-aligned against the plot, clear of the y label strip at the far left.
    const std::string text = tick_text(t, ystep);
    const int width = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, nullptr).width;
    cv::putText(img, text, {kLeft - 6 - width, p.y + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kInk);
  }
  const cv::Rect plot_area(kLeft, kTop, plot_w, plot_h);
  cv::Mat plot = img(plot_area);
  const cv::Point offset(-kLeft, -kTop);
  for (const Item& it : items_) {
    switch (it.kind) {
      case Item::Kind::line: {
        std::vector<cv::Point> run;
        const auto flush = [&] {
          if (run.size() > 1) cv::polylines(plot, run, false, it.colour, it.size, cv::LINE_AA);
          run.clear();
        };
        for (size_t i = 0; i < it.x.size() && i < it.y.size(); ++i) {
          if (!std::isfinite(it.x[i]) || !std::isfinite(it.y[i])) { flush(); continue; }
          run.push_back(px(it.x[i], it.y[i]) + offset);
        }
        flush();
        break;
      }
      case Item::Kind::points:
        for (size_t i = 0; i < it.x.size() && i < it.y.size(); ++i) {
          if (std::isfinite(it.x[i]) && std::isfinite(it.y[i])) {
            cv::circle(plot, px(it.x[i], it.y[i]) + offset, it.size, it.colour, cv::FILLED, cv::LINE_AA);
          }
        }
        break;
      case Item::Kind::rect:
      case Item::Kind::filled_rect:
        cv::rectangle(plot, px(it.x[0], it.y[0]) + offset, px(it.x[1], it.y[1]) + offset, it.colour,
                      it.kind == Item::Kind::filled_rect ? cv::FILLED : 1);
        break;
      case Item::Kind::hline: {
        const int y = px(x_lo, it.y[0]).y - kTop;
        cv::line(plot, {0, y}, {plot_w, y}, it.colour, 1, cv::LINE_AA);
        break;
      }
      case Item::Kind::bars:
        for (size_t i = 0; i + 1 < it.x.size() && i < it.y.size(); ++i) {
          cv::rectangle(plot, px(it.x[i], 0.0) + offset, px(it.x[i + 1], it.y[i]) + offset, it.colour, cv::FILLED);
          cv::rectangle(plot, px(it.x[i], 0.0) + offset, px(it.x[i + 1], it.y[i]) + offset, kInk, 1);
        }
        break;
    }
  }
  cv::rectangle(img, plot_area, kInk, 1);
  cv::putText(img, title_, {kLeft, 32}, cv::FONT_HERSHEY_SIMPLEX, 0.7, kInk, 2, cv::LINE_AA);
  cv::putText(img, x_label_, {kLeft + plot_w / 2 - 60, height_px_ - 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, kInk, 1,
              cv::LINE_AA);
  // The y label, rotated: drawn horizontally on a strip, then turned by 90 degrees.
  cv::Mat strip(24, plot_h, CV_8UC3, kWhite);
  cv::putText(strip, y_label_, {plot_h / 2 - 60, 17}, cv::FONT_HERSHEY_SIMPLEX, 0.55, kInk, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  turned.copyTo(img(cv::Rect(4, kTop, 24, plot_h)));
  // Legend of labelled items, top right.
  int row = 0;
  for (const Item& it : items_) {
    if (it.label.empty()) continue;
    const cv::Point at(kLeft + plot_w - 220, kTop + 18 + 18 * row++);
    cv::line(img, at + cv::Point(0, -4), at + cv::Point(22, -4), it.colour, 3);
    cv::putText(img, it.label, at + cv::Point(28, 0), cv::FONT_HERSHEY_SIMPLEX, 0.45, kInk, 1, cv::LINE_AA);
  }
  return img;
}

void Chart::save_png(const std::string& path) const {
  if (!cv::imwrite(path, draw())) throw std::runtime_error("cannot write " + path);
}

Chart histogram_chart(const std::vector<double>& values, int bins, const std::string& title,
                      const std::string& x_label) {
  Chart chart(title, x_label, "runs");
  std::vector<double> finite;
  for (double v : values) if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return chart;
  double lo = *std::min_element(finite.begin(), finite.end());
  double hi = *std::max_element(finite.begin(), finite.end());
  if (hi - lo < 1e-12) { lo -= 0.5; hi += 0.5; }
  std::vector<double> edges(static_cast<size_t>(bins) + 1), counts(static_cast<size_t>(bins), 0.0);
  for (int i = 0; i <= bins; ++i) edges[static_cast<size_t>(i)] = lo + (hi - lo) * i / bins;
  for (double v : finite) {
    const int b = std::min(bins - 1, static_cast<int>((v - lo) / (hi - lo) * bins));
    counts[static_cast<size_t>(b)] += 1.0;
  }
  chart.add_bars(edges, counts, cv::Scalar(200, 140, 60));
  return chart;
}

}  // namespace shelfcross::verification
