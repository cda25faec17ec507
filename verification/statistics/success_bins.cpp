#include "verification/statistics/success_bins.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

}  // namespace

void SuccessBins::add(double value, bool success) {
  auto& [n, ok] = counts_[static_cast<long>(std::floor(value / width_))];
  ++n;
  ok += success ? 1 : 0;
}

double SuccessBins::Bin::lower_95() const { return clopper_pearson_lower(successes, runs); }

std::vector<SuccessBins::Bin> SuccessBins::bins() const {
  std::vector<Bin> out;
  for (const auto& [k, counts] : counts_) {
    out.push_back({static_cast<double>(k) * width_, static_cast<double>(k + 1) * width_, counts.first, counts.second});
  }
  return out;
}

std::string SuccessBins::table_rows(double scale, int decimals, const std::string& suffix) const {
  std::ostringstream md;
  for (const Bin& b : bins()) {
    md << "| " << fixed_text(b.lo * scale, decimals) << "-" << fixed_text(b.hi * scale, decimals) << suffix << " | " << b.runs
       << " | " << b.successes << " | " << fixed_text(b.rate(), 3) << " | " << fixed_text(b.lower_95(), 3) << " |\n";
  }
  return md.str();
}

}  // namespace shelfcross::verification
