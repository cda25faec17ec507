#include "verification/scenario/scenario_yaml.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <yaml-cpp/yaml.h>

namespace shelfcross::verification::scenario_yaml {

bool valid_utf8(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const auto* const end = p + text.size();
  while (p < end) {
    const unsigned c = *p++;
    if (c < 0x80) continue;
    int more = 0;
    unsigned lo = 0x80, hi = 0xbf;  // the range of the first continuation byte
    if (c >= 0xc2 && c <= 0xdf) more = 1;
    else if (c == 0xe0) more = 2, lo = 0xa0;
    else if (c >= 0xe1 && c <= 0xef) more = 2, hi = c == 0xed ? 0x9f : 0xbf;
    else if (c == 0xf0) more = 3, lo = 0x90;
    else if (c >= 0xf1 && c <= 0xf3) more = 3;
    else if (c == 0xf4) more = 3, hi = 0x8f;
    else return false;
    if (end - p < more) return false;
    for (int k = 0; k < more; ++k, lo = 0x80, hi = 0xbf)
      if (p[k] < lo || p[k] > hi) return false;
    p += more;
  }
  return true;
}

std::string format_double(double x) {
  char buf[64];
  const double magnitude = std::abs(x);
  if (magnitude == 0.0 || (magnitude >= 1e-4 && magnitude < 1e15)) {
    for (int decimals = 0; decimals <= 20; ++decimals) {
      std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
      if (std::strtod(buf, nullptr) == x) return buf;
    }
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

std::string yaml_quoted(const std::string& s) {
  YAML::Emitter e;
  e << YAML::DoubleQuoted << s;
  return e.c_str();
}

}  // namespace shelfcross::verification::scenario_yaml
