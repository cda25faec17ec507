#include "verification/report/link_report.hpp"

#include <cmath>
#include <map>
#include <sstream>

#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/plot/plot.hpp"
#include "verification/statistics/success_bins.hpp"

namespace shelfcross::verification {

std::string link_section(const std::vector<RunRecord>& runs, const std::filesystem::path& dir) {
  constexpr double kBin = 0.005;  // 0.5 % of the video datagrams
  std::map<std::string, std::int64_t> models;
  SuccessBins bins(kBin);
  for (const RunRecord& r : runs) {
    const StoredMetrics stored = stored_metrics(r);
    if (!stored.run) {
      ++models["(not measured: " + r.outcome + ")"];
      continue;
    }
    const LinkMetrics& l = stored.run->link;
    ++models[l.model];
    if (l.video_datagrams > 0) bins.add(l.video_datagram_loss(), r.outcome == "success");
  }
  std::ostringstream md;
  md << "## The link\n\n";
  for (const auto& [model, n] : models) md << "- `" << model << "`: " << n << " runs\n";
  md << "\nPer-run figures (`link_*` rows of the metrics table): datagrams sent and lost, pictures "
        "decoded and error-concealed, commands sent and lost, replies and state records lost.\n\n";
  if (bins.empty()) return md.str();
  md << "### Success rate against video datagram loss\n\nEach run's measured loss (video datagrams lost / "
        "sent), in "
     << kBin * 100 << " % bins.\n\n| video datagram loss | runs | successes | success rate | 95 % lower bound |\n"
        "|---|---|---|---|---|\n"
     << bins.table_rows(100, 1, " %");
  std::vector<double> centre_pct, rate;
  for (const SuccessBins::Bin& b : bins.bins()) {
    centre_pct.push_back(50.0 * (b.lo + b.hi));
    rate.push_back(b.rate());
  }
  Chart chart("Success rate against video datagram loss", "video datagrams lost (%)", "success rate");
  chart.set_y_limits(0.0, 1.05);
  chart.add_line(centre_pct, rate, cv::Scalar(60, 160, 60), 2);
  chart.add_points(centre_pct, rate, cv::Scalar(60, 160, 60), 4);
  chart.add_hline(0.9, cv::Scalar(120, 120, 120), "90 %");
  chart.save_png((dir / "link_loss.png").string());
  md << "\n![success rate against video datagram loss](link_loss.png)\n\n";
  return md.str();
}

}  // namespace shelfcross::verification
