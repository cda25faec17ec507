#include "flight_sw/tello/sdk_driver.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <sstream>

namespace shelfcross::tello {
namespace {

constexpr const char* kHoverRc = "rc 0 0 0 0";
constexpr size_t kMaxReplyBytes = 256;
constexpr size_t kMaxQueue = 16;

// Reply text without the trailing "\r\n" (and blanks, NULs) real drones append.
std::string trim_reply(const std::string& raw) {
  size_t b = 0, e = raw.size();
  auto blank = [](char c) { return c == ' ' || c == '\r' || c == '\n' || c == '\t' || c == '\0'; };
  while (b < e && blank(raw[b])) ++b;
  while (e > b && blank(raw[e - 1])) --e;
  return raw.substr(b, e - b);
}

bool printable(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c <= 0x7e; });
}

}  // namespace

const char* event_kind_name(DriverEvent::Kind kind) {
  using K = DriverEvent::Kind;
  switch (kind) {
    case K::Sent: return "sent";
    case K::RcSent: return "rc_sent";
    case K::KeepAlive: return "keepalive";
    case K::Reply: return "reply";
    case K::Refused: return "refused";
    case K::Retry: return "retry";
    case K::Failed: return "failed";
    case K::Abandoned: return "abandoned";
    case K::StaleReply: return "stale_reply";
    case K::Foreign: return "foreign";
    case K::BadReply: return "bad_reply";
    case K::State: return "state";
    case K::BadState: return "bad_state";
    case K::Filtered: return "filtered";
    case K::Rejected: return "rejected";
  }
  return "?";
}

std::string DriverCounters::text() const {
  std::ostringstream s;
  s << "commands_sent=" << commands_sent << " retries=" << retries << " failed=" << failed
    << " replies=" << replies << " refusals=" << refusals << " stale_replies=" << stale_replies << " bad_replies=" << bad_replies
    << " abandoned=" << abandoned << " rc_sent=" << rc_sent << " keepalives=" << keepalives
    << " filtered=" << filtered << " rejected=" << rejected << " send_errors=" << send_errors
    << " foreign_command_datagrams=" << foreign_command_datagrams
    << " foreign_state_datagrams=" << foreign_state_datagrams << " states=" << states
    << " bad_states=" << bad_states << " stray_ok_states=" << stray_ok_states;
  return s.str();
}

SdkDriver::SdkDriver(DriverConfig config, const Clock& clock)
    : SdkDriver(config, clock, std::make_unique<UdpSocket>(config.local_ip, config.local_command_port),
                std::make_unique<UdpSocket>(config.local_ip, config.local_state_port)) {}

SdkDriver::SdkDriver(DriverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> command_channel,
                     std::unique_ptr<DatagramChannel> state_channel)
    : config_(std::move(config)),
      pacer_(config_.command_gap_ns),
      clock_(clock),
      drone_command_{config_.drone_ip, config_.drone_command_port},
      command_channel_(std::move(command_channel)),
      state_channel_(std::move(state_channel)) {
  // Refuse a bad address now, not at the first send; compare senders in canonical text form.
  char canonical[INET_ADDRSTRLEN] = {};
  const in_addr a = parse_ipv4(config_.drone_ip);
  ::inet_ntop(AF_INET, &a, canonical, sizeof canonical);
  drone_command_.ip = canonical;
}

void SdkDriver::event(DriverEvent::Kind kind, const std::string& command, const std::string& reply,
                      int attempt, int tag) {
  DriverEvent e;
  e.t_ns = clock_.now_ns();
  e.kind = kind;
  e.command = command;
  e.reply = reply;
  e.attempt = attempt;
  e.tag = tag;
  events_.push_back(std::move(e));
}

std::vector<DriverEvent> SdkDriver::take_events() {
  std::vector<DriverEvent> out;
  out.swap(events_);
  return out;
}

bool SdkDriver::submit(const std::string& text, const CommandOptions& options) {
  std::string why;
  const auto kind = sdk::classify_command(text, &why);
  if (!kind) {
    ++counters_.rejected;
    event(DriverEvent::Kind::Rejected, text, why, 0, options.tag);
    return false;
  }
  if (config_.dry_run && (*kind == sdk::CommandKind::Motion || *kind == sdk::CommandKind::Rc)) {
    ++counters_.filtered;
    event(DriverEvent::Kind::Filtered, text, "dry run: not sent", 0, options.tag);
    if (*kind != sdk::CommandKind::Rc) {
      event(DriverEvent::Kind::Reply, text, "ok", 1, options.tag);
      events_.back().synthetic = true;
    }
    return false;
  }
  if (options.urgent) {
    if (const Pending* o = pacer_.outstanding()) {
      ++counters_.abandoned;
      event(DriverEvent::Kind::Abandoned, o->text, "", o->attempt, o->options.tag);
      pacer_.complete();
      // Its reply may still come: the guard keeps it from answering the urgent command as
      // long as the gap allows; what arrives later is drained as stale.
    }
    for (const Pending& p : queue_) {
      ++counters_.abandoned;
      event(DriverEvent::Kind::Abandoned, p.text, "", 0, p.options.tag);
    }
    queue_.clear();
    rc_setpoint_.reset();
    guard_until_ns_ = 0;
  }
  if (*kind == sdk::CommandKind::Rc) {
    // The same sticks again only renew the setpoint: the steady repeat sends them.
    if (rc_setpoint_ != text) rc_new_owed_ = std::max(1, config_.rc_new_copies);
    rc_setpoint_ = text;
    rc_set_ns_ = clock_.now_ns();
    return true;
  }
  if (queue_.size() >= kMaxQueue) {
    ++counters_.rejected;
    event(DriverEvent::Kind::Rejected, text, "command queue full", 0, options.tag);
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

void SdkDriver::service() {
  const TimeNs now = clock_.now_ns();
  read_replies(now);
  read_states(now);
  check_timeout(now);
  send_next(now);
  send_rc(now);
}

void SdkDriver::read_replies(TimeNs now) {
  while (auto d = command_channel_->receive()) {
    if (!(d->from == drone_command_)) {
      ++counters_.foreign_command_datagrams;
      event(DriverEvent::Kind::Foreign, "", "command socket: from " + d->from.text());
      continue;
    }
    const std::string text = trim_reply(d->bytes);
    if (text.empty() || text.size() > kMaxReplyBytes || !printable(text)) {
      ++counters_.bad_replies;
      event(DriverEvent::Kind::BadReply, outstanding() ? pacer_.outstanding()->text : "",
            std::to_string(d->bytes.size()) + " bytes");
      continue;
    }
    // Nothing outstanding, or a refused command waiting to be re-sent: no reply is expected.
    Pending* current = pacer_.outstanding();
    if (!current || current->resend_ns) {
      ++counters_.stale_replies;
      event(DriverEvent::Kind::StaleReply, "", text);
      continue;
    }
    Pending& p = *current;
    if (p.options.retry_unless_ok && !flight_sw::is_ok_reply(text) && p.attempt <= p.retries) {
      ++counters_.refusals;
      event(DriverEvent::Kind::Refused, p.text, text, p.attempt, p.options.tag);
      p.resend_ns = now + config_.refusal_retry_ns;
      continue;
    }
    ++counters_.replies;
    event(DriverEvent::Kind::Reply, p.text, text, p.attempt, p.options.tag);
    pacer_.complete();
  }
}

void SdkDriver::read_states(TimeNs now) {
  while (auto d = state_channel_->receive()) {
    const bool from_drone = d->from.ip == drone_command_.ip &&
                            (config_.state_source_port == 0 || d->from.port == config_.state_source_port);
    if (!from_drone) {
      ++counters_.foreign_state_datagrams;
      event(DriverEvent::Kind::Foreign, "", "state socket: from " + d->from.text());
      continue;
    }
    sdk::StateParseReport report;
    auto record = sdk::parse_state_record(d->bytes, now, &report);
    const std::string raw = trim_reply(d->bytes);
    if (!record) {
      ++counters_.bad_states;
      if (raw == "ok" || raw == "OK") ++counters_.stray_ok_states;
      std::string shown = raw;
      if (!printable(raw)) shown = std::to_string(d->bytes.size()).append(" bytes, not text");
      event(DriverEvent::Kind::BadState, "", shown);
      continue;
    }
    ++counters_.states;
    last_state_ns_ = now;
    event(DriverEvent::Kind::State, "", raw);
    events_.back().state = std::move(record);
  }
}

void SdkDriver::resend(TimeNs now) {
  Pending& p = *pacer_.outstanding();
  ++counters_.retries;
  ++p.attempt;
  p.resend_ns.reset();
  event(DriverEvent::Kind::Retry, p.text, "", p.attempt, p.options.tag);
  pacer_.resent(now);
  if (transmit(now, p.text)) {
    ++counters_.commands_sent;
    event(DriverEvent::Kind::Sent, p.text, "", p.attempt, p.options.tag);
  }
}

void SdkDriver::check_timeout(TimeNs now) {
  Pending* current = pacer_.outstanding();
  if (!current) return;
  if (current->resend_ns) {
    if (now >= *current->resend_ns) resend(now);
    return;
  }
  if (!pacer_.overdue(now)) return;
  Pending& p = *current;
  if (p.attempt <= p.retries) {
    resend(now);
    return;
  }
  ++counters_.failed;
  event(DriverEvent::Kind::Failed, p.text, "", p.attempt, p.options.tag);
  pacer_.complete();
  guard_until_ns_ = now + config_.stale_guard_ns;
}

void SdkDriver::send_next(TimeNs now) {
  if (queue_.empty() || !pacer_.may_send(now)) return;
  if (now < guard_until_ns_) return;
  const bool motion = sdk::classify_command(queue_.front().text) == sdk::CommandKind::Motion;
  if (motion) {
    rc_setpoint_.reset();  // a manoeuvre ends any stick input
    // The Tello flies the last sticks it received until told otherwise. Centre them on the
    // wire first (stop_rc_repeats times, an emergency excepted): if the manoeuvre's datagram
    // is lost, the drone then hovers until the retry instead of flying on.
    if (stops_owed_ > 0 && queue_.front().text != "emergency") {
      if (!last_rc_ns_ || now - *last_rc_ns_ >= config_.rc_min_gap_ns) transmit_rc(now, kHoverRc, DriverEvent::Kind::RcSent);
      return;
    }
  }
  // Whatever waits on the command socket now answers nothing we will send: drain it.
  read_replies(now);
  Pending p = std::move(queue_.front());
  queue_.pop_front();
  p.attempt = 1;
  const TimeNs timeout_ns = p.timeout_ns;
  // Outstanding even if the OS refuses the send: the timeout and retries deal with it.
  const Pending& sent = pacer_.send(now, std::move(p), timeout_ns);
  if (transmit(now, sent.text)) {
    ++counters_.commands_sent;
    event(DriverEvent::Kind::Sent, sent.text, "", sent.attempt, sent.options.tag);
  }
}

void SdkDriver::send_rc(TimeNs now) {
  const bool gap_ok = !last_rc_ns_ || now - *last_rc_ns_ >= config_.rc_min_gap_ns;
  if (rc_setpoint_ && !outstanding() && gap_ok) {
    if (now - rc_set_ns_ >= config_.rc_hold_ns && *rc_setpoint_ != kHoverRc) {
      // Not renewed: the submitter stopped steering. Hover rather than fly on blind.
      rc_setpoint_ = kHoverRc;
      rc_set_ns_ = now;
      rc_new_owed_ = std::max(1, config_.rc_new_copies);
    }
    const bool fresh = now - rc_set_ns_ < config_.rc_hold_ns;
    const bool due = rc_new_owed_ > 0 || (fresh && (!last_rc_ns_ || now - *last_rc_ns_ >= config_.rc_period_ns));
    if (due) {
      rc_new_owed_ = std::max(0, rc_new_owed_ - 1);
      transmit_rc(now, *rc_setpoint_, DriverEvent::Kind::RcSent);
      return;
    }
  }
  if (config_.keepalive_ns > 0 && !config_.dry_run && last_any_ns_ &&
      now - *last_any_ns_ >= config_.keepalive_ns) {
    transmit_rc(now, kHoverRc, DriverEvent::Kind::KeepAlive);
  }
}

void SdkDriver::transmit_rc(TimeNs now, const std::string& text, DriverEvent::Kind kind) {
  last_rc_ns_ = now;
  if (!transmit(now, text)) return;
  ++(kind == DriverEvent::Kind::KeepAlive ? counters_.keepalives : counters_.rc_sent);
  event(kind, text);
  stops_owed_ = text == kHoverRc ? std::max(0, stops_owed_ - 1) : config_.stop_rc_repeats;
}

bool SdkDriver::transmit(TimeNs now, const std::string& text) {
  // Every datagram passes the SDK's ranges once more, whatever path it took here.
  std::string why;
  if (!sdk::classify_command(text, &why)) {
    ++counters_.rejected;
    event(DriverEvent::Kind::Rejected, text, why);
    return false;
  }
  last_any_ns_ = now;
  if (!command_channel_->send_to(drone_command_, text)) {
    ++counters_.send_errors;
    return false;
  }
  return true;
}

}  // namespace shelfcross::tello
