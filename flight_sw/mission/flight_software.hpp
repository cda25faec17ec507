#pragma once
// The flight software's one entry point, used unchanged by the co-simulation and by
// tello_pilot: stamped camera frames, state records and SDK replies in, SDK commands out.
// This is the mission (its phases' work: command_phases.hpp, airborne_phases.hpp); guidance.hpp,
// target_tracker.hpp, odometry.hpp (README "Files") the rest.
//   FlightSoftware fsw(load_flight_config("shelf.yaml"));
//   send(fsw.start(t0));                 // "command"; then "streamon", "takeoff" after "ok"s
//   for (each input in stamp order) send(fsw.step(input));
//   until fsw.finished(); fsw.result(), fsw.inventory_json()
//
// Time is the stamp of each input (t_ns); an input stamped earlier than one already handled
// is handled at the latest stamp seen. Nothing here reads a clock or draws a random number:
// the same inputs give the same commands.
//
// Phases (mission/phases.hpp: the table of transitions; each with a timeout; a timed-out
// airborne phase lands):
//   EnterSdk --ok--> StartVideo --ok--> WaitVideo --first frame, battery ok--> TakeOff
//   TakeOff --ok (or reply lost while the height says airborne)--> FindShelf
//   FindShelf --whole grid in view--> GoToViewpoint --at the optimal viewpoint, settled-->
//   TakeInventory --inventory_frames full views read, enough whole--> Approach (target = empty cell nearest
//   the image centre; forward only near the normal and, close in, once settled)
//   --corner tags leave the view, centred within tolerance on a fresh still pose--> Cross
//   --distance past the back face flown (state odometry; timed while the records are stale)-->
//   Land --ok (or the state height says down)--> Done
// Several shelves (config.layout.shelf_count > 1, a row at shelf_spacing_m): after each
// inventory but the last, the target is the empty cell nearest the next shelf's optimal
// viewpoint (docs/method.md section 1); the crossing's end hands over to FindShelf for the next shelf
// (the spacing lets it see that shelf whole from there), and only the last crossing lands.
// Conventional strategies (config.strategy.mode over_tops / around_ends): TakeInventory
// --inventory full--> Transfer: waypoints planned in the grid frame G from the last visual pose
// at the viewpoint (over the tops: straight up until the vehicle's bottom clears the top tags by
// top_clearance_m, forward to the next shelf's viewpoint distance (at least that clearance behind
// the back face), down to the viewpoint height;
// around the ends: sideways past the nearer grid end by end_clearance_m, forward, back to the
// centre line), flown on odometry (the state record's heading-frame velocities integrated, its
// height for z; heading held) with the same rc velocity commands, then FindShelf for the next
// shelf (visual re-acquisition), or Land past the last shelf (Outcome::Completed).
// Damaged pictures (CameraFrame::damaged): decisions (the phase changes above, the inventory,
// the target's re-acquisition, the crossing and the last centimetres before it) only on
// pictures with at most perception.decide_max_damage_events lost bands since their key frame;
// steering on up to steer_max_damage_events; hover on worse. A picture with more damage
// decides and steers after all when its damaged rows (CameraFrame::damaged_rows) lie
// band_margin_px clear of the rows the decision rests on; those rows are blanked first. Only
// whole pictures count toward an empty cell.
// Failsafes: no frame for video_hover_s: hover (rc 0 0 0 0); for video_land_s: land (not while
// crossing: the crossing is open loop and stopping inside the shelf is worse; not while the
// state records are gone too: the whole link is out, which the ground station rides through and
// bounds, and the video has video_land_s from the link's return). Target lost:
// hover and re-acquire from the tags; after target_lost_s re-read the shelf from the viewpoint
// if its grid is still in view on nearly whole pictures, else land. Battery below
// low_battery_pct: land (after the crossing if crossing). Corner tags leaving the view while
// not centred: back off until they are back (then approach again); after back_off_s of
// backing off or at the crossing_attempts-th off-centre arrival, re-read the shelf from the
// viewpoint. Every re-read (these and the identity check's) counts toward
// mission.identity_rereads; the next doubt lands in front of the shelf. Takeoff refused or
// unanswered: retried command_retries times, then the mission ends on the ground. Land
// unanswered: done once a fresh state record says down, else retried command_retries times;
// refused in the air (already landing, `Not joystick`): asked again every 0.5 s until the
// state height says down, for up to land_reply_s.
// A re-read that starts closer than the viewpoint and sees no tag backs straight out first.
// The line's hold (line_hold.hpp): inside commit_range_m the vehicle holds short while the
// wander of its quiet hover forecasts no room for the blind crossing; after calm_wait_s of
// that, or at the crossing_attempts-th refusal of the gate for the line's hold, the crossing
// is declined: it backs out to give_up_clearance_m and lands there ("crossing declined: ...");
// every other give-up of the approach (the re-reads spent) backs out and lands there too.
// In the crossing, while the vehicle can still stop short of the front face, a drift the state
// record shows leaving the opening stops it and backs it out (a refusal, as above).
//
// Lateral law sign (paper Fig. 19): the yaw loop keeps the target cell centred in the image,
// so the camera looks at the cell centre. A vehicle displaced to the left of the cell normal
// (y_K > 0; y left) must then be turned right to see it: psi = atan2(-y_K, -x_K) < 0. So
// psi < -psi_L means "left of the normal": move right, vy_B = -V_y; psi > psi_L means right of
// it: move left, vy_B = +V_y. Hence vy_B = bang_off_bang(psi, psi_L, V_y), which drives y_K
// and with it psi to zero: the path straightens onto the cell normal. The psi fed to the law
// is the heading at which the cell is centred (vision's heading plus the cell's remaining
// bearing e_psi), the value the yaw loop converges to, so that the yaw loop's lag does not
// enter the lateral loop (with 0.12-0.35 s of video latency it made the law push the wrong way
// a quarter of the time and kept the vehicle 5-15 cm off the normal at the crossing).
// Approach speed (eq. 10): xdot_0 forward while the line of sight is within approach_cone_rad
// of the normal (the paper's short path perpendicular to the face) and, inside
// commit_range_m, while settled (lateral law quiet for settle_s, e_z and e_psi small); 0
// otherwise, the other loops running (hover and settle; given up after settle_hold_s).
// Crossing: gated on a pose at most pose_fresh_s old taken settle_s after the last lateral
// command (so the latency hides no sideways motion), on the heading, on where the crossing
// line meets the front and back faces, and on the height the state record gives now (h less
// the cell centre's height in h's frame, measured on close, vertically still poses of the
// approach) and where the vertical speed carries it: both inside the opening between the
// beams. Flown along the straight line from the last pose through the cell centre at
// mid-depth, heading held, at crossing_speed_mps, horizontally open loop (no picture shows the
// cell from inside it) and ended when the state odometry (the records' heading-frame
// velocities integrated) has flown the line to beyond_distance_m past the back face; timed, at
// the approach's measured speed gain plus the autopilot's lag, only while the state records
// are stale, and never beyond 1.5 times that. Vertically the cell centre's height is held by
// the state height (vz = crossing_kp_z (z_cell - h)), zero vertical stick while no fresh state
// record comes.
// Vertical: dy_im = cy - v_box (pixels, > 0 when the target is above the principal point);
// e_z = dy_im * range / fy (metres, eq. 11 with k_e = fy / range); vz = PI(e_z) climbs toward
// it. Heading: dx_im = u_box - cx; e_psi = atan(-dx_im / fx) (eq. 13-14 with k_dpsi = 1,
// > 0 when the target is left); yaw_rate = PI(e_psi) turns left toward it (CCW positive,
// sent as d = -yaw_rate * rc_per_radps_yaw, the SDK's d being clockwise).

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/control/sticks.hpp"
#include "flight_sw/mission/airborne_phases.hpp"
#include "flight_sw/mission/command_phases.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/mission.hpp"
#include "flight_sw/mission/phases.hpp"
#include "flight_sw/mission/telemetry.hpp"
#include "flight_sw/mission/video_intake.hpp"
#include "flight_sw/perception/inventory.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// The host's periodic timer. Timeouts, retries and failsafes advance on every input; this
/// one carries nothing else, so that they still fire when no message arrives at all (the
/// first "command" lost: no reply, no state record, no video until it is resent).
/// tello_pilot feeds one per loop turn, the co-simulation one every 1 / cosim.fsw_tick_hz.
struct ClockTick {
  TimeNs t_ns = 0;
};

using Input = std::variant<CameraFrame, StateRecord, SdkReply, ClockTick>;

/// The mission: the phases' units return their decisions (mission.hpp) and it takes them.
class FlightSoftware final {
 public:
  /// Throws std::invalid_argument for an invalid configuration (validate_flight_config).
  explicit FlightSoftware(FlightConfig config);

  /// The opening command ("command"); call once, before step.
  std::vector<SdkCommand> start(TimeNs t_ns);
  /// Everything else: one input, the commands it causes (each stamped with the input's time).
  std::vector<SdkCommand> step(const Input& input);

  const Telemetry& telemetry() const { return facts_.telemetry; }
  Phase phase() const { return facts_.phase.current(); }
  bool finished() const { return phase() == Phase::Done; }
  MissionResult result() const { return commands_.result(); }
  /// The inventory of the current shelf (the only one with a single-shelf layout).
  const Inventory& inventory() const { return shelves_.survey().inventory(); }
  /// Inventories of the shelves finished before the current one.
  const std::vector<Inventory>& finished_inventories() const { return shelves_.survey().finished(); }
  /// Every decided box of every shelf so far, labelled with its shelf index.
  std::vector<BoxEntry> all_boxes() const;
  /// One shelf: Inventory::to_json. Several: {"shelves":[<Inventory::to_json>, ...]}.
  std::string inventory_json() const;
  int shelf_index() const { return shelves_.shelf(); }
  const FlightConfig& config() const { return *config_; }

 private:
  // The decisions: every one taken in one place, `take`; every phase entered in one, `enter`
  /// Takes a unit's decision (Decision, mission.hpp), and the rest of the airborne step it
  /// resumes, `pic` the picture the step had (if it was one's).
  void take(Decision decision, const Picture* pic = nullptr);
  /// Enters `phase`, `event` written to the telemetry: every phase's start clears its timers
  /// and restarts the PI loops, then the phase's own entry (the SDK command it asks for).
  /// Throws std::logic_error on a transition the table (mission/phases.cpp) lacks.
  void enter(Phase phase, const std::string& event);
  /// Sends the sticks flown when an rc datagram is due (`force`: now), airborne and with no
  /// non-rc command outstanding; otherwise nothing.
  void emit_rc(bool force);
  // Pictures and timers (replies and state records: `step` hands them to the units)
  void on_frame(const CameraFrame& frame);
  void supervise();

  std::shared_ptr<const FlightConfig> config_;  ///< the one configuration every unit reads
  MissionFacts facts_;       ///< now, the phase, the last state record, the odometry, the telemetry
  CommandPhases commands_;   ///< the non-rc commands, what their replies mean, the result
  Sticks sticks_;            ///< the velocity flown, its PI loops and its rc datagrams
  VideoIntake video_;        ///< the pictures' worth, the damaged rows blanked, the video's stall
  AirbornePhases shelves_;   ///< the airborne phases across the shelves, their units
  std::vector<SdkCommand> out_;  ///< the commands of the input being handled
};

}  // namespace shelfcross::flight_sw
