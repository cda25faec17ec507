#pragma once
// What the crossing's own state records say of the Tello's position hold (docs/method.md
// section 7, "What the watch can and cannot catch"). In the crossing no picture shows the cell;
// the state record (10 Hz) is all there is, and two of the Tello's own senses change under it
// as it enters the shelf:
//
//   the range    tof reads the first surface below: the floor in front of the shelf, then the
//                cell's bottom beam and the box of the cell below (a step of 0.3-0.7 m). A
//                height hold that follows the range by a share beta climbs beta times the
//                step while its own estimate, and so h, stays put. Over one surface the
//                range's change is the vehicle's climb; across a step (|tof's change - vgz dt|
//                > kRangeStep_m between two records: no motion the crossing commands moves it
//                that far in 0.1 s) the vertical speed's vgz dt is (the fused estimate's
//                vertical speed, which the range does not enter). Their sum over the crossing
//                is how far the vehicle climbed; h's change less it is the hold's range offset
//                o, counted once the range has stepped and |o| has reached kHoldOffsetSeen_m
//                (h's and tof's noise, a few centimetres, and the 0.1 m/s steps of vgz over a
//                step's interval stay below it), and from then on for the rest of the crossing.
//                The vehicle is at h - o, not h: the crossing holds and judges that height.
//   the VPS      below its working range (about 0.3 m: over the box of the cell below) or
//                over a plain surface the VPS gives no velocity, and vgx, vgy read exactly 0:
//                the position hold is lost, the vehicle drifts with the air, and the odometry
//                stands still. kVpsLostRecords records in a row reading 0 exactly while the
//                crossing flies at crossing_speed_mps (every record of a flying VPS reads its
//                0.4 m/s as 0.3-0.5) say the VPS is lost, for the rest of the crossing: the
//                watch no longer judges the line on the odometry. What the odometry misses is
//                flown blind: each record reading 0 while flying adds its interval at the
//                speed the VPS read on the crossing's last kBlindSpeedRecords flying records
//                (the vehicle's own speed in this crossing, not the approach's speed gain:
//                with the hold gone the Tello tilts for the sticks' speed in still air and
//                keeps about it), and the line's progress is the odometry's plus that. Once
//                the VPS reads again (the floor behind the shelf), the odometry goes on.

#include <deque>
#include <optional>
#include <utility>

#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

/// A change of the range reading between two records that vertical motion does not explain by
/// this much is a step of the surface below (file comment).
constexpr double kRangeStep_m = 0.08;
/// The hold's range offset is counted from this size on (file comment).
constexpr double kHoldOffsetSeen_m = 0.06;
/// This many records in a row with vgx = vgy = 0 exactly, while flying, say the VPS is lost.
constexpr int kVpsLostRecords = 2;
/// The hold offset's rate is taken over this many records.
constexpr int kRateRecords = 3;
/// The speed flown blind is the mean horizontal speed of this many flying records (0.5 s:
/// the VPS's noise and its 0.1 m/s steps averaged to a few centimetres a second).
constexpr int kBlindSpeedRecords = 5;

class CrossingReadings {
 public:
  /// The crossing's records, the first at its start; `flying`: the crossing commands a speed
  /// the VPS would read (it has flown longer than the autopilot's lag since it began).
  void on_state(const StateRecord& s, bool flying);
  /// The height hold's range offset o, m: h's change less the vehicle's climb (file comment),
  /// once the range has stepped and |o| has reached kHoldOffsetSeen_m; 0 before. The vehicle
  /// is at h - o.
  double hold_offset_m() const;
  /// How fast o changes, m/s: over the last kRateRecords records (0.3 s: a record's 1 cm steps
  /// of h and tof read 3 cm/s there, not 10); 0 before o is counted.
  double hold_offset_rate_mps() const;
  bool range_stepped() const { return range_stepped_; }
  /// Since kVpsLostRecords records in a row read no horizontal speed while flying: for the rest
  /// of the crossing, since the odometry missed what the vehicle flew meanwhile.
  bool vps_lost() const { return vps_lost_; }
  /// How far the vehicle flew while the VPS read nothing, m (file comment): 0 while it reads.
  double blind_m() const { return blind_m_; }
  /// The horizontal speed the VPS read on the last kBlindSpeedRecords flying records, m/s;
  /// empty before there are that many.
  std::optional<double> speed_mps() const;

 private:
  std::optional<StateRecord> first_, last_;
  std::deque<std::pair<TimeNs, double>> offsets_;  ///< o of the last kRateRecords + 1 records
  double climbed_m_ = 0.0;  ///< the vehicle's climb since the first record (file comment)
  bool range_stepped_ = false;
  bool offset_seen_ = false;
  int vps_zero_records_ = 0;
  bool vps_lost_ = false;
  std::deque<double> speeds_mps_;  ///< the last kBlindSpeedRecords flying records' read speeds
  double blind_m_ = 0.0;
};

}  // namespace shelfcross::flight_sw
