#pragma once
// Each subcommand of `shelfcross` lives in its own cmd_<name>.cpp and registers itself here
// at static-initialisation time, so adding a subcommand touches no other file.
//
//   static const shelfcross::app::CommandRegistration reg{"plant", "Fly plant + autopilot open loop",
//       [](CLI::App& sub) {
//         auto opts = std::make_shared<PlantOptions>();   // owned by the returned action
//         sub.add_option("--seconds", opts->seconds_s, "...")->required();
//         return [opts]() -> int { ...run...; return 0; };
//       }};
//
// The setup function adds the subcommand's options and returns the action to run when the
// subcommand is chosen; the action returns the process exit code. Bad user input throws
// UsageError or config::ConfigError; main prints it and exits with code 2.

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace shelfcross::app {

using CommandAction = std::function<int()>;
using CommandSetup = std::function<CommandAction(CLI::App&)>;

struct CommandEntry {
  std::string name;
  std::string description;
  CommandSetup setup;
};

inline std::vector<CommandEntry>& command_registry() {
  static std::vector<CommandEntry> entries;
  return entries;
}

struct CommandRegistration {
  CommandRegistration(std::string name, std::string description, CommandSetup setup) {
    command_registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

/// Thrown by actions for bad user input: main prints the message and exits with code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace shelfcross::app
