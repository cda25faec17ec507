#pragma once
// The senses' dispersions (dispersion_table.hpp: vps_noise_mps, ...) and the keys of the
// scenario's `senses:` section (plant/tello_senses.hpp) each replaces: one table, used to apply
// a run's draws and to read or set a scenario's value by its dispersion's name.

#include <string>

#include "plant/tello_senses.hpp"

namespace shelfcross::verification {

/// The key of `senses` that the senses dispersion `name` replaces; nullptr for a name that is
/// not one of them.
double* senses_dispersed_field(plant::SensesParams& senses, const std::string& name);

/// Whether `name` draws one of the Tello's own senses, the camera's rolling shutter
/// (`camera_readout_s`) or the air near surfaces (`ground_effect_coeff`, `ceiling_effect_coeff`):
/// the dispersions a scenario with the documented senses adds to the world of the truth.
bool is_senses_dispersion(const std::string& name);

}  // namespace shelfcross::verification
