#pragma once
// What a system identification needs of a tello_pilot flight log (flight_sw/tello/README.md,
// "The flight log"): the rc datagrams as they left for the drone, the state records as they
// arrived, the frame stamps, and when the drone was airborne. Read strictly: a log that is
// not a tello_pilot log, cut mid-line, without its `end` line, or whose streams go back in
// time is refused with a FlightLogFormatError reading "file:line: reason". state_send_times:
// the state records' times as a fit takes them.

#include <array>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::identify {

struct FlightLogFormatError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One rc datagram on the wire: the sticks a (right), b (forward), c (up), d (clockwise),
/// each -100..100, at the program-clock time it was sent (a setpoint, a repeat or a
/// keep-alive: the drone holds the newest it received).
struct RcSent {
  TimeNs t_ns = 0;
  std::array<int, 4> sticks{};
};

/// One video frame's stamps (program clock): its last datagram received, decoded and in the
/// mailbox, taken by the loop.
struct FrameStamps {
  TimeNs rx_ns = 0;
  TimeNs handed_ns = 0;
  TimeNs taken_ns = 0;
  bool damaged = false;
};

struct FlightRecord {
  std::string source;                  ///< the file, for messages
  std::string mode;                    ///< the start line's `mode` ("" for a mission)
  std::vector<RcSent> rc;              ///< in send order
  std::vector<StateRecord> states;     ///< in receive order; t_ns = receive time
  std::vector<FrameStamps> frames;     ///< in hand-over order
  /// The takeoff's `ok` received; its reply lost, the stick program's start (tello_pilot starts
  /// it once the state shows the drone airborne).
  std::optional<TimeNs> takeoff_ok_ns;
  std::optional<TimeNs> land_sent_ns;  ///< the first `land` sent after it
  TimeNs start_ns = 0, end_ns = 0;     ///< the start and end lines
  int lines = 0;
  int bad_states = 0;                  ///< `bad_state` lines (datagrams the driver dropped)
};

/// Reads and checks a flight log. Throws FlightLogFormatError ("file:line: reason") or
/// std::runtime_error when the file cannot be read.
FlightRecord read_flight_record(const std::string& path);
/// The same from a stream; `name` stands for the file in messages.
FlightRecord parse_flight_record(std::istream& in, const std::string& name);

/// The state records' times (ns, the log's clock) as the fit takes them. A drone sends its
/// state at a steady rate (the Tello 10 Hz) and a record arrives no earlier than it left; the
/// log stamps it when the program read it. Records read closer together than the period were
/// held up on the way (the program busy, the link's queue) and carry the time they were read,
/// up to several periods after the state they hold: at a heading turning 1 rad/s, a record read
/// 0.3 s late is 0.3 rad off the model. So each record's time is at most its stamp and at least
/// the median period before the next record's (a pass backwards from the last): a burst of
/// records after a stall goes back onto the sender's period, a record read on time keeps its
/// stamp (the next one comes a period later). Exact for a steady sender when no record of the
/// burst was lost (with one lost, the burst's earlier records stay up to a period late); a
/// sender's jitter moves a record by at most that jitter.
std::vector<TimeNs> state_send_times(const FlightRecord& record);

}  // namespace shelfcross::identify
