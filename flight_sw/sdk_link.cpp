#include "flight_sw/sdk_link.hpp"

namespace shelfcross::flight_sw {

void SdkLink::request(std::string text, double reply_timeout_s) {
  queued_ = Queued{std::move(text), seconds_to_ns(reply_timeout_s)};
}

void SdkLink::poll(TimeNs now_ns, std::vector<SdkCommand>& out) {
  if (!queued_ || !pacer_.may_send(now_ns)) return;
  Queued q = std::move(*queued_);
  queued_.reset();
  out.push_back({now_ns, pacer_.send(now_ns, std::move(q.text), q.timeout_ns)});
}

std::optional<SdkLink::Completion> SdkLink::on_reply(const SdkReply& reply) {
  std::optional<std::string> command = pacer_.complete();
  if (!command) {
    ++stale_replies_;
    return std::nullopt;
  }
  return Completion{std::move(*command), reply.text, is_ok_reply(reply.text), false};
}

std::optional<SdkLink::Completion> SdkLink::check_timeout(TimeNs now_ns) {
  if (!pacer_.overdue(now_ns)) return std::nullopt;
  return Completion{std::move(*pacer_.complete()), "", false, true};
}

}  // namespace shelfcross::flight_sw
