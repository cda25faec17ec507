#pragma once
// One axis of the Tello's response to its sticks, as the simulated autopilot models it
// (plant/autopilot.hpp): the stick passes a first-order reference model
//
//     tau v_ref'(t) = K u(t - d) - v_ref(t),   p_ref' = v_ref,
//
// u the stick / 100 held piecewise constant from each rc datagram's send time, K the gain at
// full stick, tau the time constant, d the dead time from the datagram leaving the computer to
// the state record showing its effect (the command's way to the drone and the state record's
// way back); and the vehicle follows the reference through the autopilot's own loops
// (TrackingLoop: its position, velocity, attitude and rate loops with the scenario's gains,
// linearised: small tilt, no saturation). The loops are the simulator's: fitting through them
// answers the calibration's question, which parameters of the simulated Tello reproduce this
// drone. TrackingLoop::Kind::none is the bare first-order response (v = v_ref).
// The response is observed either directly (a velocity) or through its integral plus an
// unknown offset per segment of the record (a height, a heading: the integral has the finer
// resolution in the SDK's integer cm and degrees, and the offsets absorb slow drift).
//
// Fit: least squares over the samples, separable (variable projection): for fixed (tau, d)
// the model is linear in K and the offsets, solved exactly; (tau, d) by a grid search then
// Nelder-Mead. Uncertainty: a moving-block residual bootstrap (Kuensch 1989): the residuals'
// blocks of block_s are resampled with replacement onto the fitted response and the fit is
// repeated; the 2.5 and 97.5 % percentiles of the refits are the 95 % interval. Blocks keep the
// residuals' correlation (gusts, quantisation of a smooth response), which resampling single
// residuals would pretend away.

#include <cstdint>
#include <vector>

namespace shelfcross::identify {

/// A piecewise-constant input: u[i] from t_s[i] until t_s[i + 1]; 0 before t_s[0].
struct PiecewiseInput {
  std::vector<double> t_s;
  std::vector<double> u;
};

enum class Observation { direct, integral };

/// How the vehicle follows the reference (v_ref, p_ref), per axis, as plant/autopilot.cpp's
/// control() does it, linearised:
///   acceleration (horizontal, vertical): a_cmd = a_ff + k_v (v_ref + k_p (p_ref - p) - v) + I,
///     I' = k_i (v_ref + k_p (p_ref - p) - v), a_ff = (K u - v_ref) / tau; the acceleration
///     follows a_cmd through the attitude loops (tilt = a / g: angle gain k_att, rate gain
///     k_rate, a critically damped second order) or, when those are 0, through the motors'
///     first-order lag; v' = a - drag v.
///   rate (yaw): w_d = v_ref + k_p (p_ref - p); the rate loop, a PI (gains k_rate, k_rate_i),
///     gives the angular acceleration: v' = k_rate (w_d - v) + I_r, I_r' = k_rate_i (w_d - v).
struct TrackingLoop {
  enum class Kind { none, acceleration, rate };
  Kind kind = Kind::none;
  double pos_gain_per_s = 0.0;
  double vel_gain_per_s = 0.0;
  double vel_integral_gain_per_s2 = 0.0;
  double att_gain_per_s = 0.0;
  double rate_gain_per_s = 0.0;
  double rate_integral_gain_per_s2 = 0.0;  ///< rate kind: the rate loop's integral
  double lag_s = 0.0;        ///< acceleration's first-order lag when att_gain_per_s is 0
  double drag_per_s = 0.0;
  double step_s = 0.002;     ///< integration step (the autopilot's 500 Hz tick)
};

/// One axis's record: the input and the observed samples (times ascending).
struct AxisRecord {
  PiecewiseInput input;
  std::vector<double> t_s;
  std::vector<double> y;
  std::vector<int> segment;  ///< per sample, 0..segments-1 (integral: one offset each)
  int segments = 1;
  Observation observation = Observation::direct;
  TrackingLoop loop;
  /// The resolution y arrives in, when it is coarse against the response (the SDK's velocities
  /// in integer dm/s: 0.1); 0: fine enough for least squares (see fit_axis).
  double quantum = 0.0;
};

/// The vehicle's response to the input at unit gain (at rest before the first input), at the
/// times `t_s` (ascending): its velocity, or its position counted from the first time on.
/// With Kind::none: tau x' = u(t - d) - x and x's integral. tau_s must be > 0 and the input's
/// times and values of one length (asserted).
std::vector<double> unit_response(const PiecewiseInput& input, double tau_s, double delay_s,
                                  const std::vector<double>& t_s, Observation observation,
                                  const TrackingLoop& loop = {});

struct FitBounds {
  double tau_min_s = 0.03, tau_max_s = 3.0;
  double delay_min_s = -0.2, delay_max_s = 1.0;  ///< below 0: the stamps of a command and of a state record are taken at different points of the loop
};

struct AxisFit {
  double gain = 0.0;
  double tau_s = 0.0;
  double delay_s = 0.0;
  std::vector<double> offsets;   ///< integral observation: one per segment
  std::vector<double> fitted;    ///< the model at the samples
  double rms = 0.0;              ///< residual root mean square
  double sigma = 0.0;            ///< quantised records: the noise's standard deviation (ML)
  bool at_bound = false;         ///< tau or d ended on a bound of the search
};

/// Least-squares fit (see the file comment). Precondition: at least 4 samples.
/// A record with a quantum (direct observations only) is then refined by maximum likelihood
/// of its rounded samples: y_k = q round((f_k + e_k) / q), e_k ~ N(0, sigma^2) independent, so
/// P(y_k) = Phi((y_k + q/2 - f_k) / sigma) - Phi((y_k - q/2 - f_k) / sigma), over (K, tau, d,
/// sigma), sigma at least q / 20. Least squares on such samples is biased: a plateau of 0.247
/// m/s read as 0.2 for two seconds pulls the fit by 0.047 m/s, which the likelihood knows to be
/// within the reading's rounding. The floor on sigma stands for what blurs a reading's last
/// digit besides noise (the sampling instant, known to a few ms, times the response's slope);
/// without it a noise-free record's likelihood would be a hard set membership. A floor as
/// large as the rounding itself (q / sqrt(12)) would bias the fit the way least squares does:
/// plateaus pulled to the middle of their readings, the dead time and the time constant traded.
AxisFit fit_axis(const AxisRecord& record, const FitBounds& bounds = {});

/// log(Phi(b) - Phi(a)) for a < b (Phi the standard normal CDF), accurate in either tail: the
/// likelihood of a rounded reading.
double log_normal_mass(double a, double b);

/// A value with its 95 % bootstrap interval and the replicates it came from. `margin` is a
/// stated model-error allowance (identification.hpp), already added to both ends of [lo, hi];
/// stddev and the replicates are the bootstrap's alone.
struct Interval {
  double value = 0.0;
  double lo = 0.0, hi = 0.0;
  double stddev = 0.0;
  double margin = 0.0;
  std::vector<double> replicates;
};

/// The fit and its moving-block residual bootstrap (`replicates` refits, blocks of block_s,
/// resampling drawn from a RandomStream seeded from `seed`). Quantised records: a parametric
/// bootstrap instead, records drawn from the fitted likelihood (the fitted response plus
/// noise of standard deviation sigma, rounded to the quantum) and refitted by maximum
/// likelihood; the noise is AR(1) with the residuals' lag-1 correlation between consecutive
/// records, so that a disturbance lasting several records (a gust) counts once, not each time.
struct AxisIdentification {
  AxisFit fit;
  Interval gain, tau_s, delay_s;
};
/// A dead time known from elsewhere is given by bounds with delay_min_s == delay_max_s, and
/// its bootstrap replicates by `delay_replicates` (replicate i refits with the i-th, so that
/// its uncertainty passes on).
AxisIdentification identify_axis(const AxisRecord& record, int replicates, std::uint64_t seed, double block_s = 2.0,
                                 const FitBounds& bounds = {}, const std::vector<double>* delay_replicates = nullptr);

/// The 2.5 and 97.5 % percentiles, the mean and standard deviation of `replicates` around
/// `value`; the replicates are kept in their order.
Interval interval_of(double value, std::vector<double> replicates);

}  // namespace shelfcross::identify
