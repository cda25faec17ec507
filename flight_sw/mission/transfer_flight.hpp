#pragma once
// The Transfer phase of the conventional strategies (over_tops / around_ends,
// flight_software.hpp): waypoints planned in the grid frame G of the shelf just read
// (guidance.hpp, transfer_waypoints_G), turned into the odometry frame O (odometry.hpp) about
// the vehicle's position, and flown one leg at a time on the state records.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/navigation.hpp"

namespace shelfcross::flight_sw {

class TransferFlight {
 public:
  /// Plans the legs from the grid pose `pose_G` at the viewpoint: G's x axis lies at heading
  /// (state_yaw_rad - pose_G.yaw_rad) in O, about the vehicle's odometry position `p_O_m`;
  /// heights are offsets from the state's. The first leg starts at now_ns.
  void plan(const FlightConfig& config, const PoseEstimate& pose_G, double state_yaw_rad, const Eigen::Vector3d& p_O_m,
            const Eigen::Vector3d& viewpoint_G_m, bool last_shelf, TimeNs now_ns);

  /// One state record's progress: the next waypoint once within `tolerance_m` (a new leg from
  /// now_ns).
  struct Progress {
    bool arrived = false;     ///< the last waypoint reached: the transfer is over
    bool next_leg = false;    ///< a waypoint reached, the next one ahead
    Eigen::Vector3d e_O_m = Eigen::Vector3d::Zero();  ///< to the current waypoint, in O
  };
  Progress on_state(const Eigen::Vector3d& p_O_m, double tolerance_m, TimeNs now_ns);

  /// How long the current leg has lasted (bounded by strategy.transfer_leg_s).
  double leg_s(TimeNs now_ns) const { return ns_to_seconds(now_ns - leg_start_ns_); }
  std::size_t waypoint() const { return waypoint_; }
  /// The heading held: the shelf normal in O.
  double hold_yaw_O_rad() const { return hold_yaw_O_rad_; }

 private:
  std::vector<Eigen::Vector3d> waypoints_O_m_;
  std::size_t waypoint_ = 0;
  double hold_yaw_O_rad_ = 0.0;
  TimeNs leg_start_ns_ = 0;
};

}  // namespace shelfcross::flight_sw
