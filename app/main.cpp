// shelfcross: the verification suite's one program. Subcommands register themselves
// (command_registry.hpp); they are listed by `shelfcross --help`.

#include <algorithm>
#include <exception>
#include <iostream>
#include <memory>

#include "command_registry.hpp"
#include "config/strict_yaml.hpp"
#include "verification/campaign/results_store.hpp"

int main(int argc, char** argv) {
  using namespace shelfcross::app;
  CLI::App app{"shelfcross: verify and fly a vision-guided MAV that crosses warehouse shelves"};
  app.require_subcommand(1);
  auto& entries = command_registry();
  std::sort(entries.begin(), entries.end(),
            [](const CommandEntry& a, const CommandEntry& b) { return a.name < b.name; });
  std::vector<std::pair<CLI::App*, CommandAction>> actions;
  for (const auto& entry : entries) {
    CLI::App* sub = app.add_subcommand(entry.name, entry.description);
    // A command without a description is internal (`worker`): left out of --help.
    if (entry.description.empty()) sub->group("");
    actions.emplace_back(sub, entry.setup(*sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (auto& [sub, action] : actions) {
      if (sub->parsed()) return action();
    }
  } catch (const shelfcross::config::ConfigError& e) {
    std::cerr << "shelfcross: " << e.what() << "\n";
    return 2;
  } catch (const shelfcross::verification::ResultsMismatch& e) {
    std::cerr << "shelfcross: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "shelfcross: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shelfcross: error: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
