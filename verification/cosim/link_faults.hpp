#pragma once
// The co-simulation's link faults from a scenario's `cosim.link` keys: one fault model
// (DatagramFaults, verification/world/datagram_faults.hpp) for both links. The sdk link hands
// it to the simulated Tello, which draws it datagram by datagram; the ideal link draws it
// message by message, with the same seed (the run's), so a scenario's faults fall the same way
// on both links where the messages are the same. What each key does on each link:
// verification/scenario/link_settings.hpp.

#include "verification/scenario/link_settings.hpp"
#include "verification/world/datagram_faults.hpp"

namespace shelfcross::verification {

/// The fault settings of a link: latencies in ms, each channel's loss and duplication, the
/// whole-frame loss, late replies, refusals, the lost-command injection, the video stall
/// (on only when video_stall_start_s >= 0 and video_stall_duration_s > 0), the bursts and the
/// outages (the fixed one on only when outage_start_s >= 0 and outage_duration_s > 0). Requires settings
/// checked by the scenario reader; not checked again here. Does not throw.
EmulatorFaults link_faults(const LinkSettings& link);

}  // namespace shelfcross::verification
