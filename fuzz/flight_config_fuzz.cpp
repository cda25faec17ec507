// The flight software's configuration loader (flight_sw/config.hpp) on arbitrary text: it
// refuses with config::ConfigError only (anything else escaping is a finding), and what it
// accepts passes the checks for configurations built by code (validate_flight_config).
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "config/strict_yaml.hpp"
#include "flight_sw/config.hpp"

using namespace shelfcross;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  flight_sw::FlightConfig c;
  try {
    c = flight_sw::parse_flight_config(text, "fuzz.yaml");
  } catch (const config::ConfigError&) {
    return 0;
  }
  try {
    flight_sw::validate_flight_config(c);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "flight config: accepted from text but invalid: %s\n", e.what());
    std::abort();
  }
  return 0;
}
