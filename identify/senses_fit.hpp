#pragma once
// The Tello's own senses (plant/tello_senses.hpp) from a calibration flight with the senses
// block (flight_sw/tello/calibration_manoeuvre.hpp: a still hover, then a slow pass over a
// board of known height). Names are the scenario's dispersions (dispersion_table.hpp).
//
// The still hover (the longest stretch of centred sticks while flying, at least min_still_s,
// less 2 s after the last stick and 0.5 s before the next): each reading is
//     y_k = q round((m(t_k) + e_k) / q),  e_k ~ N(0, sigma^2) independent,
// m its slow wander (the hold's answer to the air, the barometer's drift), q the SDK's
// resolution (h, tof: 1 cm; baro: 0.01; vgx, vgy: 0.1 m/s). m is taken as the mean of the
// half_window records on each side (the record itself left out; 3 records: a wider mean leaves
// more of the wander in the residuals), so a residual's spread is
// sigma^2 (1 + 1/n) plus the mean's own rounding, q^2 / (12 n); sigma is the maximum of the
// rounded readings' likelihood (the interval mass of each reading). A reading at the SDK's
// coarse 0.1 m/s mostly reads 0 when the noise is a few cm/s: the likelihood knows that too
// (how often a reading leaves 0), where a standard deviation of the readings would not.
// 95 % interval: the likelihood-ratio interval (chi-square, 1 degree: 3.84) of the log-likelihood
// scaled by n_eff / n. A scatter's estimate varies as 2 sigma^4 sum_ij rho_ij^2 (rho_ij the
// residuals' correlations), not 2 sigma^4 n, so n_eff = n^2 / sum_ij rho_ij^2: the moving mean
// itself correlates neighbouring residuals (exactly known for white readings: 1.30 n at
// half_window 3), and a wander the mean leaves behind adds its own (from the residuals'
// autocorrelations); the larger of the two counts.
// Below half a rounding step the interval is [0, at least q / 2]: the readings cannot tell such
// a noise from the rounding of the wander.
//   height_noise_m   h's noise. h is the hold's estimate, which the hold keeps at its target.
//   baro_noise_m     baro's noise about the barometric height.
//   tof_noise_m      tof's noise (over the floor).
//   vps_noise_mps    an upper bound only: vgx and vgy are the VPS's estimate, which the hold
//                    keeps at zero; its scatter is the VPS's noise and the drone's answer to the
//                    air, which a log cannot tell apart. The interval is [0, upper end].
// Not identifiable from a log, and so not estimated: the VPS's bias (vps_bias_stddev_mps). The
// hold flies the estimate, so vgx, vgy read about 0 whatever the bias, and the drone's true
// drift (at -bias) is in no reading of the state record; one flight would anyway give one draw
// of the bias, not its spread. The barometer's drift (baro_drift_m_per_sqrt_s) shows in baro -
// tof over a flat floor, but over the hover's 15 s it is millimetres under the baro's noise.
//
// The height hold (the board pass): with H the board's stated height, over a flat floor and the
// board, h = z + d + o - z_0 and tof = tof_ground + z - rest - H u(t), so
//     y = h - tof = c + H u(t) + o(t) + d(t) + noise,
// the drone's own height z cancelling (u: 1 while the range sensor sees the board). The hold's
// range offset o follows -beta (H u + d) with the time constant tau. An edge of u lies between
// two records where tof steps by at least 0.6 H and y by at least 0.2 H the other way (its time
// taken in the middle of them); the steps of tof at the edges must average H (within 5 cm or
// 20 %), else the board is not the one stated and nothing is fitted. With F_tau[u] the
// first-order response to u,
//     y - H u = c_w + s_w t - beta H F_tau[u](t) + e,
// an offset and a slope per window (a pass, from 3 s before its edge onto the board to 6 s after
// its edge off it), fitted by least squares in (beta H, c_w, s_w) for each tau, tau in
// [kTauMin_s, kTauMax_s] by a grid and golden section. Intervals: 2.5 and 97.5 % percentiles of
// refits on the fit plus the residuals in moving blocks of block_s (within each window), the
// edges' times drawn anew within their two records, and a drift drawn anew (the barometer's
// drift is no straight line over a pass; the residuals' blocks cannot carry a wander that slow):
// a walk d* as y holds it, d* - beta F_tau[d*], of d's intensity: the floor's over (1 - beta)
// and, where beta > 0.5, at least baro - tof's (drift_track.hpp).
//   height_hold_range_blend      beta: 0 the hold ignores the range reading, 1 it follows it.
//   height_hold_time_constant_s  tau, only when beta's interval lies above kFollowsFrom (a
//                                hold that barely follows cannot be timed) and tau's below
//                                kTauIdentifiableBelow_s.
// The flight must stay below the hold's range_below_m (it is not estimated): fly the pass at the
// height of interest.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "identify/flight_record.hpp"
#include "identify/response_fit.hpp"

namespace shelfcross::identify {

struct SensesOptions {
  std::optional<double> board_height_m;  ///< stated; none: the height hold is not identified
  int bootstrap_replicates = 200;
  std::uint64_t seed = 1;
  double block_s = 2.0;
  double min_still_s = 10.0;
  int half_window = 3;  ///< records each side of the still hover's moving mean (0.3 s at 10 Hz)
};

/// The height hold follows the range reading when beta's interval lies above this.
inline constexpr double kFollowsFrom = 0.05;
/// The time constants searched (s): from faster than the records can show to slower than the
/// scenarios' plausible 2 s; a slower hold is a drift over the pass's window and trades with its
/// slope. An interval that reaches kTauIdentifiableBelow_s is not identified.
inline constexpr double kTauMin_s = 0.02, kTauMax_s = 5.0;
inline constexpr double kTauIdentifiableBelow_s = 4.5;
/// Board heights the pass can use (m): a step well above the readings' cm, below the VPS's
/// range at the calibration's height.
inline constexpr double kBoardHeightMin_m = 0.1, kBoardHeightMax_m = 0.6;

/// The noise of rounded readings around a slow mean (see the file comment).
struct RoundedNoise {
  double sigma = 0.0;
  double lo = 0.0, hi = 0.0;  ///< likelihood-ratio interval at n_eff
  double rho = 0.0;           ///< residuals' lag-1 correlation (at least 0)
  double n_eff = 0.0;
  int n = 0;
};
/// series: one or more stretches of one reading (their likelihoods add). Needs 20 readings.
RoundedNoise fit_rounded_noise(const std::vector<std::vector<double>>& series, double quantum, int half_window);

/// The board pass's records and fit, for the report's plot.
struct BoardPassFit {
  std::vector<double> t_s;       ///< since the takeoff's ok
  std::vector<double> y_m;       ///< h - tof - H u
  std::vector<double> fitted_m;
  std::vector<double> edges_s;   ///< the edges' times (middle of their records)
  std::vector<double> steps_m;   ///< each edge's step down of tof (+H onto the board, -H off it)
  std::vector<int> window;
  double rms_m = 0.0;
};

struct SensesIdentification {
  bool still_found = false;
  double still_from_s = 0.0, still_to_s = 0.0;  ///< since the takeoff's ok
  int still_records = 0;
  std::map<std::string, Interval> parameters;         ///< dispersion names
  std::map<std::string, std::string> not_identified;  ///< name: why
  std::map<std::string, std::string> how;             ///< name: what the interval means
  std::optional<double> board_height_m;
  BoardPassFit board;
};

/// Never throws for a flight without the senses block: what it cannot identify it says why.
SensesIdentification identify_senses(const FlightRecord& record, const SensesOptions& options);

/// The dispersion names identify_senses may fill, in the report's order.
const std::vector<std::string>& senses_parameter_names();

}  // namespace shelfcross::identify
