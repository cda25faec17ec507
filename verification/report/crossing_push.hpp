#pragma once
// How far the air pushed a crossing off its line, from what a campaign stored: the margin a
// crossing must hold across the cell, measured where the posts are.

#include <optional>

#include "verification/campaign/stored_run.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {

/// The crossing's push: the largest distance across the cell, |y_S - y_S(centre)|, of the body
/// origin from the centre line of the cell of shelf 0 that the run crossed (WorldTruth::crossed),
/// over the trace's samples where any part of the vehicle lies within the shelf's depth,
/// -l/2 <= x_S <= depth + l/2 (l the vehicle's length), in the last such pass that reaches the
/// shelf's mid-depth (the crossing; a pass stopped at the front face does not). A crossing in a
/// column touches a post when the push exceeds crossing_room_m(): the room the crossing's lateral
/// margin is there to hold. From the stored trace at about 10 Hz, so it can miss the peak by the
/// drift of 0.05 s (under 3 mm at 0.05 m/s across).
/// Nothing when the run crossed no cell of shelf 0 or its trace has no sample inside.
std::optional<double> crossing_push_m(const Scenario& scenario, const StoredMetrics& metrics, const StoredTrace& trace);

/// The room a crossing of column `column` of shelf 0 has across the cell before the vehicle's
/// side touches a post, at a still heading: half the column's pitch - half a post - half the
/// vehicle's width (11.4 cm in a 34 cm column of the test shelf).
double crossing_room_m(const Scenario& scenario, int column);

}  // namespace shelfcross::verification
