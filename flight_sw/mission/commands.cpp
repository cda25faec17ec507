#include "flight_sw/mission/commands.hpp"

#include <utility>

namespace shelfcross::flight_sw {

MissionCommands::MissionCommands(const Timeouts& timeouts)
    : pacer_(seconds_to_ns(timeouts.command_gap_s)), retries_(timeouts.command_retries) {}

void MissionCommands::queue(std::string text, double reply_timeout_s) {
  queued_ = Waiting{std::move(text), seconds_to_ns(reply_timeout_s)};
}

void MissionCommands::ask(std::string command, double reply_timeout_s) {
  attempts_ = 0;
  again_.reset();
  queue(std::move(command), reply_timeout_s);
}

bool MissionCommands::retry(const std::string& command, double reply_timeout_s) {
  if (attempts_ >= retries_) return false;
  ++attempts_;
  queue(command, reply_timeout_s);
  return true;
}

void MissionCommands::ask_again_at(std::string command, double reply_timeout_s, TimeNs at_ns) {
  again_ = Again{std::move(command), reply_timeout_s, at_ns};
}

std::optional<MissionCommands::Completion> MissionCommands::on_reply(const SdkReply& reply) {
  std::optional<std::string> command = pacer_.complete();
  if (!command) {
    ++stale_replies_;
    return std::nullopt;
  }
  return Completion{std::move(*command), reply.text, is_ok_reply(reply.text), false};
}

std::optional<MissionCommands::Completion> MissionCommands::check_timeout(TimeNs now_ns) {
  if (!pacer_.overdue(now_ns)) return std::nullopt;
  return Completion{std::move(*pacer_.complete()), "", false, true};
}

void MissionCommands::poll(TimeNs now_ns, std::vector<SdkCommand>& out) {
  if (again_ && now_ns >= again_->at_ns) {
    queue(std::move(again_->command), again_->reply_timeout_s);
    again_.reset();
  }
  if (!queued_ || !pacer_.may_send(now_ns)) return;
  Waiting w = std::move(*queued_);
  queued_.reset();
  out.push_back({now_ns, pacer_.send(now_ns, std::move(w.text), w.timeout_ns)});
}

}  // namespace shelfcross::flight_sw
