#include "flight_sw/sdk_link.hpp"

#include <cctype>

namespace shelfcross::flight_sw {

bool is_ok_reply(const std::string& text) {
  size_t b = 0, e = text.size();
  while (b < e && std::isspace(static_cast<unsigned char>(text[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1]))) --e;
  return e - b == 2 && std::tolower(static_cast<unsigned char>(text[b])) == 'o' &&
         std::tolower(static_cast<unsigned char>(text[b + 1])) == 'k';
}

void SdkLink::request(std::string text, double reply_timeout_s) {
  queued_ = Pending{std::move(text), seconds_to_ns(reply_timeout_s), 0};
}

void SdkLink::poll(TimeNs now_ns, std::vector<SdkCommand>& out) {
  if (!queued_ || outstanding_) return;
  if (last_sent_ns_ && now_ns - *last_sent_ns_ < gap_ns_) return;
  outstanding_ = std::move(queued_);
  queued_.reset();
  outstanding_->sent_ns = now_ns;
  last_sent_ns_ = now_ns;
  out.push_back({now_ns, outstanding_->text});
}

std::optional<SdkLink::Completion> SdkLink::on_reply(const SdkReply& reply) {
  if (!outstanding_) {
    ++stale_replies_;
    return std::nullopt;
  }
  Completion c{outstanding_->text, reply.text, is_ok_reply(reply.text), false};
  outstanding_.reset();
  return c;
}

std::optional<SdkLink::Completion> SdkLink::check_timeout(TimeNs now_ns) {
  if (!outstanding_ || now_ns - outstanding_->sent_ns < outstanding_->timeout_ns) {
    return std::nullopt;
  }
  Completion c{outstanding_->text, "", false, true};
  outstanding_.reset();
  return c;
}

}  // namespace shelfcross::flight_sw
