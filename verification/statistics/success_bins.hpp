#pragma once
// Runs binned by a per-run value (latency, datagram loss, ...): each bin's runs and
// successes, its success rate and one-sided 95 % Clopper-Pearson lower bound, for the report's
// "success rate against X" sections.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace shelfcross::verification {

class SuccessBins {
 public:
  /// Bins [k w, (k + 1) w) of width w; requires w > 0 and finite values in add() (not
  /// checked: a NaN value lands in an arbitrary bin).
  explicit SuccessBins(double width) : width_(width) {}
  void add(double value, bool success);
  bool empty() const { return counts_.empty(); }

  struct Bin {
    double lo = 0.0, hi = 0.0;
    std::int64_t runs = 0, successes = 0;
    double rate() const { return static_cast<double>(successes) / static_cast<double>(runs); }
    double lower_95() const;
  };
  /// The non-empty bins, lowest first.
  std::vector<Bin> bins() const;
  /// Markdown rows "| lo-hi suffix | runs | successes | rate | lower bound |", the edges
  /// multiplied by `scale` and printed with `decimals`.
  std::string table_rows(double scale, int decimals, const std::string& suffix = "") const;

 private:
  double width_;
  std::map<long, std::pair<std::int64_t, std::int64_t>> counts_;  // bin -> (runs, successes)
};

}  // namespace shelfcross::verification
