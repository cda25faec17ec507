#include "flight_sw/text.hpp"

#include <cstdio>

namespace shelfcross::flight_sw {

std::string cell_text(CellIndex c) {
  // Appended piece by piece: GCC 12 misreads "literal" + std::string as an overlapping copy
  // (-Wrestrict, a false positive in its own <string>).
  std::string text = "L";
  text += std::to_string(c.level);
  text += " C";
  text += std::to_string(c.column);
  return text;
}

std::string format_m(double m) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", m);
  return b;
}

}  // namespace shelfcross::flight_sw
