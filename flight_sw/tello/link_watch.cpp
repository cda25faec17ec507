#include "flight_sw/tello/link_watch.hpp"

namespace shelfcross::tello {

LinkVerdict LinkWatch::check(TimeNs now_ns, TimeNs last_state_ns) {
  if (out_since_ns_ && last_state_ns > *out_since_ns_) {
    last_outage_s_ = ns_to_seconds(last_state_ns - *out_since_ns_);
    out_since_ns_.reset();
    back_ns_ = last_state_ns;
    return LinkVerdict::Back;
  }
  const TimeNs silent_ns = now_ns - last_state_ns;
  if (silent_ns > give_up_after_ns_) return LinkVerdict::GiveUp;
  if (out_since_ns_) return LinkVerdict::Out;
  if (silent_ns > lost_after_ns_) {
    out_since_ns_ = last_state_ns;
    return LinkVerdict::Lost;
  }
  return LinkVerdict::Live;
}

}  // namespace shelfcross::tello
