#pragma once
// The senses' dispersions (dispersion_table.hpp: vps_noise_mps, ...) and the keys of the
// scenario's `senses:` section (plant/tello_senses.hpp) each replaces: one table, used to apply
// a run's draws and to read or set a scenario's value by its dispersion's name.

#include <string>

#include "plant/tello_senses.hpp"

namespace shelfcross::verification {

struct Scenario;

/// The key of `senses` that the senses dispersion `name` replaces; nullptr for a name that is
/// not one of them.
double* senses_dispersed_field(plant::SensesParams& senses, const std::string& name);

/// Whether `name` draws one of the Tello's own senses, the camera's rolling shutter
/// (`camera_readout_s`) or the air near surfaces (`ground_effect_coeff`, `ceiling_effect_coeff`):
/// the dispersions a scenario with the documented senses adds to the world of the truth.
bool is_senses_dispersion(const std::string& name);

/// The scenario in the world of the truth: its `senses` at the identity, a global shutter, no
/// air near surfaces, none of their dispersions; every other key and dispersion as it was (so a
/// run's other draws are unchanged: each dispersion has its own stream). What
/// scripts/senses_variants.py writes as a scenario's `none` variant.
Scenario without_senses(Scenario scenario);

}  // namespace shelfcross::verification
