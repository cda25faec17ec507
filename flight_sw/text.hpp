#pragma once
// Texts the mission writes into its events and outcomes' reasons (flight_software.hpp).

#include <string>

#include "shelfcross/cell_index.hpp"

namespace shelfcross::flight_sw {

/// "L<level> C<column>".
std::string cell_text(CellIndex cell);
/// A length for logs: metres with two decimals ("0.42").
std::string format_m(double m);
/// Why an approach that never centred gives up, once the re-reads are spent.
inline constexpr const char* kCouldNotCentre = "could not centre on the target cell";

}  // namespace shelfcross::flight_sw
