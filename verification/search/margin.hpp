#pragma once
// Margins of one run: how close it came to each failure class, in one number per class,
// negative when the run failed in that class (a continuous measure for the rare-event search,
// rare_event.hpp; documented in docs/search.md). They are computed from what a run stores
// (its outcome and metrics JSON, cosim.hpp) and the nominal scenario, so they apply to
// campaign runs as well as to search runs.
//
//   contact   m: the minimum clearance between the vehicle box and any shelf part while near a
//             shelf (WorldTruth::min_clearance_m); after a contact with anything (a shelf part,
//             a wall, the ceiling) minus its penetration depth, and at most -1e-6 m, so every
//             contact is negative; NaN when the run never came near a shelf and touched nothing.
//             A near miss of a wall does not lower it (clearance is to shelves only).
//   near_miss m: the contact margin less the scenario's cosim.near_miss_m: below zero when the
//             least clearance fell below the near-miss threshold. The class counts as failed
//             only for a near miss proper (is_near_miss, stored_run.hpp: no contact), so its
//             estimate is of near misses apart from contacts; a contact's margin is below zero
//             too, so the search is drawn toward contacts as it is toward near misses (a run
//             that touched passed closer than any near miss).
//   crossing  m: the room left at the front face of the cell the vehicle entered: with e_y, e_z
//             the body origin's offsets from the cell centre at the front face (entry_offset_*),
//             the cell's clear half-opening h_y = (column pitch - post thickness) / 2,
//             h_z = (row pitch - beam thickness - t) / 2 with t the shelf's deck thickness (0
//             without decks), and the vehicle box's half-extents s_y, s_z
//             (size_m / 2 + cosim.vehicle_margin_m),
//                 min(h_y - s_y - |e_y|, h_z - s_z - |e_z - t / 2|)
//             (the box taken level and square to the shelf): negative when the box overlapped
//             the opening's edge as it entered. The cell is the one crossed, else the target,
//             else (neither known) the shelf's narrowest column and lowest row pitch. NaN when
//             the vehicle never entered a cell of shelf 0.
//   mission   (no unit): success: 1 - mission_time_s / cosim.timeout_s, the time to spare
//             (in (0, 1]); any other outcome: -(1 - 0.9 c), c = shelves crossed through their
//             chosen cell / mission shelves: -1 when no shelf was crossed, -0.1 when every
//             shelf was and the mission still failed (a wrong inventory, a contact after the
//             last crossing, no landing).
//             What it sees coming: the flight software's centring give-up ("could not centre
//             on the target cell") comes at its third off-centre arrival at the crossing gate
//             (or after 5 s of backing off), and each earlier one costs a back-off and a new
//             approach (seconds of mission time), so a success's time to spare falls with the
//             arrivals it used. Measured on 405 runs of the gust scenarios (docs/search.md,
//             "What it finds, measured"): successes slower than 23 s (the undisturbed mission takes 21-22 s) are
//             3 % below 0.2 m/s of gust intensity, 44 % at 0.4-0.5 m/s and all at 0.5-0.6 m/s,
//             where 4 runs in 13 fail. Below about 0.3 m/s it barely moves: there the ranking of
//             runs by it is mostly the seed's noise.

#include <optional>
#include <string>

#include "verification/cosim/run_result.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {

enum class FailureClass { contact, crossing, mission, near_miss };
const char* failure_class_name(FailureClass c);
/// "contact", "crossing", "mission", "near_miss"; nullopt for anything else.
std::optional<FailureClass> parse_failure_class(const std::string& name);
inline constexpr FailureClass kFailureClasses[] = {FailureClass::contact, FailureClass::crossing,
                                                   FailureClass::mission, FailureClass::near_miss};

struct RunMargins {
  double contact_m = 0.0;
  double crossing_m = 0.0;
  double mission = 0.0;
  double near_miss_m = 0.0;
  bool near_miss_run = false;  ///< is_near_miss (stored_run.hpp) at the scenario's threshold
  double of(FailureClass c) const;
  /// The margin of class c is a number below zero; a near miss is the run being one (a contact,
  /// whose near-miss margin is below zero too, is not).
  bool failed(FailureClass c) const { return c == FailureClass::near_miss ? near_miss_run : of(c) < 0.0; }
};

/// The margins of a run of `nominal` from its stored outcome and metrics (none for a run lost
/// with its worker). Does not throw: a margin that needs a metric the run has not got (no
/// clearance measured, no crossing, no metrics at all) is NaN, which failed() counts as not
/// failed.
RunMargins run_margins(const Scenario& nominal, const std::string& outcome, const std::optional<RunMetrics>& metrics);

}  // namespace shelfcross::verification
