// The scenario loader on arbitrary text: it refuses with config::ConfigError only (anything
// else escaping is a finding), and for every text it accepts, writing the scenario and reading
// it back gives the same scenario and the same text (scenario.hpp:
// parse_scenario(write_scenario(s)) == s, and writing that again gives the same text).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "config/strict_yaml.hpp"
#include "verification/scenario/scenario.hpp"

using namespace shelfcross;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  verification::Scenario s;
  try {
    s = verification::parse_scenario(text, "fuzz.yaml");
  } catch (const config::ConfigError&) {
    return 0;  // refused with file:line: the documented outcome for bad input
  }
  const std::string written = verification::write_scenario(s);
  verification::Scenario back;
  try {
    back = verification::parse_scenario(written, "written.yaml");
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "scenario: the written form is refused: %s\n--- written ---\n%s\n", e.what(),
                 written.c_str());
    std::abort();
  }
  if (!(back == s)) {
    std::fprintf(stderr, "scenario: parse(write(s)) != s\n--- written ---\n%s\n--- again ---\n%s\n", written.c_str(),
                 verification::write_scenario(back).c_str());
    std::abort();
  }
  if (verification::write_scenario(back) != written) {
    std::fprintf(stderr, "scenario: writing twice differs\n--- written ---\n%s\n", written.c_str());
    std::abort();
  }
  return 0;
}
