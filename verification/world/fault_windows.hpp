#pragma once
// A link's faults that last: losses in bursts (a two-state Gilbert-Elliott chain per channel)
// and outages (nothing passes on any channel, either way: a Wi-Fi re-association). Both are
// windows on the run's time line, quiet spells and faulty spells in turn, each spell's length
// drawn from a stream of its own as the time line is first asked about, so that the answer at a
// time is the same whatever order the times are asked in (the channels ask at their own
// instants, not quite in order) and no other draw of the link moves.
//
// The chain in continuous time: the good state lasts Exp(good_mean_s), the bad one
// Exp(bad_mean_s); a datagram on air in the good state is lost with the channel's own loss
// probability, in the bad state with bad_loss. Its stationary share of bad time is
// bad_mean / (good_mean + bad_mean), its long-run loss rate
//   (good_mean * loss + bad_mean * bad_loss) / (good_mean + bad_mean),
// and a burst on a channel carrying r datagrams a second loses about r * bad_mean_s * bad_loss
// of them in a row (video: about 240 datagrams a second, 8 a frame at 30 frames/s by
// BM_EncodeRendered; state records 10 a second).
// Every channel starts the run in the good state.

#include <optional>
#include <vector>

#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::verification {

/// Losses in bursts: the two-state chain's settings, the same for every channel (each channel
/// runs its own chain).
struct BurstLoss {
  double bad_loss = 0.5;     ///< loss probability of a datagram in the bad state, 0..1
  double bad_mean_s = 0.0;   ///< mean stay in the bad state (exponential); 0: no bursts
  double good_mean_s = 10.0; ///< mean stay in the good state (exponential), > 0
  bool on() const { return bad_mean_s > 0.0; }
  bool operator==(const BurstLoss&) const = default;
};

/// Outages of every channel at once: at random (a quiet spell of Exp(interval_mean_s), then an
/// outage of uniform [min_s, max_s], in turn) and one at a fixed time (start_s, duration_s: what
/// a scenario's dispersions draw).
struct LinkOutages {
  double interval_mean_s = 0.0;  ///< mean quiet spell before each random outage; 0: none at random
  double min_s = 1.0;            ///< a random outage lasts uniform in [min_s, max_s]
  double max_s = 5.0;
  std::optional<double> start_s; ///< one more outage from start_s (s since the start) ...
  double duration_s = 0.0;       ///< ... lasting this long
  bool operator==(const LinkOutages&) const = default;
};

/// One window of a fault: [start_ns, end_ns).
struct FaultWindow {
  TimeNs start_ns = 0;
  TimeNs end_ns = 0;
};

/// Quiet and faulty spells in turn from time 0, the quiet first, each spell's length drawn from
/// `stream` (one draw a spell) when the time line is first asked about past the spells drawn.
class FaultWindows {
 public:
  /// A spell's length in seconds: exponential of mean `mean_s` when mean_s > 0, else uniform in
  /// [min_s, max_s]. One draw of the stream either way.
  struct Spell {
    double mean_s = 0.0;
    double min_s = 0.0;
    double max_s = 0.0;
    double draw_s(RandomStream& stream) const;
  };
  /// Never faulty.
  FaultWindows() = default;
  /// Requires quiet and fault spells of positive length on average (not checked).
  FaultWindows(Spell quiet, Spell fault, RandomStream stream);
  /// Whether t falls in a faulty spell; false for t < 0 and for a process never faulty.
  bool active(TimeNs t);
  /// The faulty spells drawn so far (those up to the latest time asked about, and one more).
  const std::vector<FaultWindow>& windows() const { return windows_; }

 private:
  Spell quiet_, fault_;
  std::optional<RandomStream> stream_;
  std::vector<FaultWindow> windows_;
};

/// The burst chain's good and bad spells as FaultWindows (the bad ones faulty); never faulty when
/// the bursts are off.
FaultWindows burst_windows(const BurstLoss& bursts, RandomStream stream);
/// The random outages as FaultWindows; never faulty when interval_mean_s is 0.
FaultWindows outage_windows(const LinkOutages& outages, RandomStream stream);

}  // namespace shelfcross::verification
