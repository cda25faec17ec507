#include "flight_sw/mission_commands.hpp"

#include <utility>

namespace shelfcross::flight_sw {

MissionCommands::MissionCommands(const Timeouts& timeouts)
    : link_(timeouts.command_gap_s), retries_(timeouts.command_retries) {}

void MissionCommands::ask(std::string command, double reply_timeout_s) {
  attempts_ = 0;
  again_.reset();
  link_.request(std::move(command), reply_timeout_s);
}

bool MissionCommands::retry(const Completion& c, double reply_timeout_s) {
  if (attempts_ >= retries_) return false;
  ++attempts_;
  link_.request(c.command, reply_timeout_s);
  return true;
}

void MissionCommands::ask_again_at(std::string command, double reply_timeout_s, TimeNs at_ns) {
  again_ = Again{std::move(command), reply_timeout_s, at_ns};
}

void MissionCommands::poll(TimeNs now_ns, std::vector<SdkCommand>& out) {
  if (again_ && now_ns >= again_->at_ns) {
    link_.request(std::move(again_->command), again_->reply_timeout_s);
    again_.reset();
  }
  link_.poll(now_ns, out);
}

}  // namespace shelfcross::flight_sw
