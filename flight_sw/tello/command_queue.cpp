#include "flight_sw/tello/command_queue.hpp"

#include <algorithm>

namespace shelfcross::tello {
namespace {

constexpr size_t kMaxReplyBytes = 256;
constexpr size_t kMaxQueue = 16;

}  // namespace

CommandQueue::CommandQueue(const DriverConfig& config, CommandWire& wire, DriverRecorder& recorder)
    : config_(config), wire_(wire), recorder_(recorder), pacer_(config.command_gap_ns) {}

bool CommandQueue::submit(const std::string& text, const CommandOptions& options) {
  if (queue_.size() >= kMaxQueue) {
    ++recorder_.counters().rejected;
    recorder_.add(DriverEvent::Kind::Rejected, text, "command queue full", 0, options.tag);
    return false;
  }
  Pending p;
  p.text = text;
  p.options = options;
  p.timeout_ns = options.timeout_ns.value_or(config_.timeouts.timeout_for(text));
  p.retries = std::max(0, options.retries.value_or(config_.retries));
  if (options.urgent) {
    queue_.push_front(std::move(p));
  } else {
    queue_.push_back(std::move(p));
  }
  return true;
}

void CommandQueue::abandon_all() {
  if (const Pending* o = pacer_.outstanding()) {
    ++recorder_.counters().abandoned;
    recorder_.add(DriverEvent::Kind::Abandoned, o->text, "", o->attempt, o->options.tag);
    pacer_.complete();
    // Its reply may still come. The gap keeps it from answering the next command: the pacer's
    // gap still runs from this command's last send, so the next one goes no sooner than
    // command_gap_ns after it, and a reply that arrives before then answers nothing (none is
    // outstanding: read_replies, and send_next's drain just before the send) and is dropped
    // as stale. A reply later than the gap would be taken for the next command's. The stale
    // guard, which would hold the next command back longer, is cleared below.
  }
  for (const Pending& p : queue_) {
    ++recorder_.counters().abandoned;
    recorder_.add(DriverEvent::Kind::Abandoned, p.text, "", 0, p.options.tag);
  }
  queue_.clear();
  guard_until_ns_ = 0;
}

void CommandQueue::read_replies(TimeNs now) {
  DriverCounters& counters = recorder_.counters();
  while (auto bytes = wire_.receive()) {
    const std::string text = trim_reply(*bytes);
    Pending* current = pacer_.outstanding();
    if (text.empty() || text.size() > kMaxReplyBytes || !printable(text)) {
      ++counters.bad_replies;
      recorder_.add(DriverEvent::Kind::BadReply, current ? current->text : "",
                    std::to_string(bytes->size()) + " bytes");
      continue;
    }
    // Nothing outstanding, or a refused command waiting to be re-sent: no reply is expected.
    if (!current || current->resend_ns) {
      ++counters.stale_replies;
      recorder_.add(DriverEvent::Kind::StaleReply, "", text);
      continue;
    }
    Pending& p = *current;
    if (p.options.retry_unless_ok && !flight_sw::is_ok_reply(text) && p.attempt <= p.retries) {
      ++counters.refusals;
      recorder_.add(DriverEvent::Kind::Refused, p.text, text, p.attempt, p.options.tag);
      p.resend_ns = now + config_.refusal_retry_ns;
      continue;
    }
    ++counters.replies;
    recorder_.add(DriverEvent::Kind::Reply, p.text, text, p.attempt, p.options.tag);
    pacer_.complete();
  }
}

void CommandQueue::transmit(TimeNs now, const Pending& p) {
  if (wire_.transmit(now, p.text)) {
    ++recorder_.counters().commands_sent;
    recorder_.add(DriverEvent::Kind::Sent, p.text, "", p.attempt, p.options.tag);
  }
}

void CommandQueue::resend(TimeNs now) {
  Pending& p = *pacer_.outstanding();
  ++recorder_.counters().retries;
  ++p.attempt;
  p.resend_ns.reset();
  recorder_.add(DriverEvent::Kind::Retry, p.text, "", p.attempt, p.options.tag);
  pacer_.resent(now);
  transmit(now, p);
}

void CommandQueue::check_timeout(TimeNs now) {
  Pending* current = pacer_.outstanding();
  if (!current) return;
  if (current->resend_ns) {
    if (now >= *current->resend_ns) resend(now);
    return;
  }
  if (!pacer_.overdue(now)) return;
  if (current->attempt <= current->retries) {
    resend(now);
    return;
  }
  ++recorder_.counters().failed;
  recorder_.add(DriverEvent::Kind::Failed, current->text, "", current->attempt, current->options.tag);
  pacer_.complete();
  guard_until_ns_ = now + config_.stale_guard_ns;
}

bool CommandQueue::resend_unheard(TimeNs now, const std::string& text) {
  const Pending* current = pacer_.outstanding();
  if (!current || current->text != text || current->resend_ns || current->attempt > current->retries) return false;
  resend(now);
  return true;
}

const std::string* CommandQueue::next_due(TimeNs now) const {
  if (queue_.empty() || !pacer_.may_send(now) || now < guard_until_ns_) return nullptr;
  return &queue_.front().text;
}

void CommandQueue::send_next(TimeNs now) {
  // Whatever waits on the command socket now answers nothing we will send: drain it.
  read_replies(now);
  Pending p = std::move(queue_.front());
  queue_.pop_front();
  p.attempt = 1;
  const TimeNs timeout_ns = p.timeout_ns;
  // Outstanding even if the OS refuses the send: the timeout and retries deal with it.
  transmit(now, pacer_.send(now, std::move(p), timeout_ns));
}

}  // namespace shelfcross::tello
