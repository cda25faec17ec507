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

}  // namespace shelfcross::verification
