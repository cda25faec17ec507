#include "flight_sw/tello/rc_repeater.hpp"

#include <algorithm>

namespace shelfcross::tello {

void RcRepeater::set(const std::string& text, TimeNs now) {
  if (setpoint_ != text) new_owed_ = std::max(1, config_.rc_new_copies);
  setpoint_ = text;
  set_ns_ = now;
}

bool RcRepeater::gap_passed(TimeNs now) const {
  return !last_rc_ns_ || now - *last_rc_ns_ >= config_.rc_min_gap_ns;
}

std::optional<std::string> RcRepeater::due(TimeNs now) {
  if (!setpoint_ || !gap_passed(now)) return std::nullopt;
  if (now - set_ns_ >= config_.rc_hold_ns && *setpoint_ != kHoverRc) {
    // Not renewed: the submitter stopped steering. Hover rather than fly on blind.
    setpoint_ = kHoverRc;
    set_ns_ = now;
    new_owed_ = std::max(1, config_.rc_new_copies);
  }
  const bool fresh = now - set_ns_ < config_.rc_hold_ns;
  const bool due = new_owed_ > 0 || (fresh && (!last_rc_ns_ || now - *last_rc_ns_ >= config_.rc_period_ns));
  if (!due) return std::nullopt;
  new_owed_ = std::max(0, new_owed_ - 1);
  return *setpoint_;
}

void RcRepeater::went_out(const std::string& text) {
  stops_owed_ = text == kHoverRc ? std::max(0, stops_owed_ - 1) : config_.stop_rc_repeats;
}

}  // namespace shelfcross::tello
