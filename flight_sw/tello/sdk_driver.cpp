#include "flight_sw/tello/sdk_driver.hpp"

namespace shelfcross::tello {

SdkDriver::SdkDriver(DriverConfig config, const Clock& clock)
    : SdkDriver(config, clock, std::make_unique<UdpSocket>(config.local_ip, config.local_command_port),
                std::make_unique<UdpSocket>(config.local_ip, config.local_state_port)) {}

SdkDriver::SdkDriver(DriverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> command_channel,
                     std::unique_ptr<DatagramChannel> state_channel)
    : config_(std::move(config)),
      clock_(clock),
      recorder_(clock),
      wire_(config_.drone_ip, config_.drone_command_port, std::move(command_channel), recorder_),
      state_(wire_.drone_ip(), config_.state_source_port, std::move(state_channel), recorder_),
      commands_(config_, wire_, recorder_),
      rc_(config_) {}

bool SdkDriver::submit(const std::string& text, const CommandOptions& options) {
  std::string why;
  const auto kind = sdk::classify_command(text, &why);
  DriverCounters& counters = recorder_.counters();
  if (!kind) {
    ++counters.rejected;
    recorder_.add(DriverEvent::Kind::Rejected, text, why, 0, options.tag);
    return false;
  }
  if (config_.dry_run && (*kind == sdk::CommandKind::Motion || *kind == sdk::CommandKind::Rc)) {
    ++counters.filtered;
    recorder_.add(DriverEvent::Kind::Filtered, text, "dry run: not sent", 0, options.tag);
    if (*kind != sdk::CommandKind::Rc) recorder_.add(DriverEvent::Kind::Reply, text, "ok", 1, options.tag).synthetic = true;
    return false;
  }
  if (options.urgent) {
    commands_.abandon_all();
    rc_.clear();
  }
  if (*kind == sdk::CommandKind::Rc) {
    rc_.set(text, clock_.now_ns());
    return true;
  }
  return commands_.submit(text, options);
}

void SdkDriver::service() {
  const TimeNs now = clock_.now_ns();
  commands_.read_replies(now);
  state_.read(now);
  commands_.check_timeout(now);
  send_next(now);
  send_rc(now);
}

void SdkDriver::send_next(TimeNs now) {
  const std::string* next = commands_.next_due(now);
  if (!next) return;
  if (sdk::classify_command(*next) == sdk::CommandKind::Motion) {
    rc_.clear();  // a manoeuvre ends any stick input
    // The Tello flies the last sticks it received until told otherwise. Centre them on the
    // wire first (stop_rc_repeats times, an emergency excepted): if the manoeuvre's datagram
    // is lost, the drone then hovers until the retry instead of flying on.
    if (rc_.stops_owed() && *next != "emergency") {
      if (rc_.gap_passed(now)) transmit_rc(now, kHoverRc, DriverEvent::Kind::RcSent);
      return;
    }
  }
  commands_.send_next(now);
}

void SdkDriver::send_rc(TimeNs now) {
  if (!commands_.outstanding()) {
    if (const std::optional<std::string> rc = rc_.due(now)) {
      transmit_rc(now, *rc, DriverEvent::Kind::RcSent);
      return;
    }
  }
  const std::optional<TimeNs> last_sent_ns = wire_.last_sent_ns();
  if (config_.keepalive_ns > 0 && !config_.dry_run && last_sent_ns && now - *last_sent_ns >= config_.keepalive_ns) {
    transmit_rc(now, kHoverRc, DriverEvent::Kind::KeepAlive);
  }
}

void SdkDriver::transmit_rc(TimeNs now, const std::string& text, DriverEvent::Kind kind) {
  rc_.attempted(now);
  if (!wire_.transmit(now, text)) return;
  DriverCounters& counters = recorder_.counters();
  ++(kind == DriverEvent::Kind::KeepAlive ? counters.keepalives : counters.rc_sent);
  recorder_.add(kind, text);
  rc_.went_out(text);
}

}  // namespace shelfcross::tello
