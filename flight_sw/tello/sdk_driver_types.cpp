#include "flight_sw/tello/sdk_driver_types.hpp"

#include <algorithm>
#include <sstream>

namespace shelfcross::tello {

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

DriverEvent& DriverRecorder::add(DriverEvent::Kind kind, const std::string& command, const std::string& reply,
                                 int attempt, int tag) {
  DriverEvent e;
  e.t_ns = clock_.now_ns();
  e.kind = kind;
  e.command = command;
  e.reply = reply;
  e.attempt = attempt;
  e.tag = tag;
  events_.push_back(std::move(e));
  return events_.back();
}

std::vector<DriverEvent> DriverRecorder::take() {
  std::vector<DriverEvent> out;
  out.swap(events_);
  return out;
}

}  // namespace shelfcross::tello
