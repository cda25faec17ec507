#pragma once
// The Tello SDK's command text, parsed into typed commands with the SDK's range rules
// (docs/tello_sdk.md). The one grammar of the SDK in shelfcross: the simulated firmware
// (plant::Autopilot), the `shelfcross plant` command files and the Tello emulator parse with
// it; the driver (flight_sw/tello/sdk_driver) checks every text it sends with
// classify_command, which is this parser plus the canonical form.
//
// Units stay the SDK's here (cm, degrees, cm/s, -100..100 sticks); the autopilot converts.
// A refused text carries the reply a real Tello gives:
//   unknown verb                      -> "unknown command: <text>"
//   a number outside its range        -> "out of range"
//   wrong argument count, not integer -> "error"
// plus a human-readable reason for error messages (file:line: reason).

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "shelfcross/time.hpp"

namespace shelfcross::sdk {

enum class Verb {
  // control
  command, takeoff, land, emergency, stop, streamon, streamoff,
  up, down, left, right, forward, back, cw, ccw, flip, go, curve,
  // set
  speed, rc,
  // read
  speed_q, battery_q, time_q, height_q, temp_q, attitude_q, baro_q, tof_q, wifi_q, sdk_q, sn_q, acceleration_q,
};

struct Command {
  Verb verb = Verb::command;
  /// Integer arguments in the SDK's order and units (rc: a b c d; go: x y z speed; ...).
  std::array<int, 7> args{};
  int arg_count = 0;
  char flip_direction = 0;  ///< 'l', 'r', 'f', 'b' for flip
  bool operator==(const Command&) const = default;
};

struct ParseError {
  enum class Kind { unknown_command, out_of_range, malformed };
  Kind kind = Kind::malformed;
  std::string reply;   ///< what the Tello answers
  std::string reason;  ///< for people
  bool operator==(const ParseError&) const = default;
};

/// Parses one command datagram. Leading/trailing whitespace and a trailing "\r\n" are ignored;
/// verbs are case-sensitive lower case, as the firmware expects. Any bytes; never throws: a
/// datagram that is not a command gives a ParseError saying why.
std::variant<Command, ParseError> parse(std::string_view text);

/// The verb as spelled on the wire ("takeoff", "battery?", ...).
std::string_view verb_text(Verb verb);
/// The canonical wire text of a command ("rc 0 50 0 0").
std::string to_text(const Command& command);

bool is_read(Verb verb);        ///< "...?" commands: answered at once with a value
bool is_manoeuvre(Verb verb);   ///< takeoff, land, moves, turns, flip, go, curve: deferred reply

// ---- The sending side: what the driver may put on the wire ----

enum class CommandKind {
  Control,  ///< command, streamon, streamoff: session and video, no motion
  Read,     ///< battery?, height?, ...: answered with a value
  Motion,   ///< takeoff, land, emergency, stop, moves, turns, flip, go, curve, speed
  Rc,       ///< rc a b c d: never answered
};

/// The kind of a parsed command's verb.
CommandKind kind_of(Verb verb);

/// The command's kind when `text` is a command parse() accepts, written in canonical form:
/// printable ASCII only and `text == to_text(*parse(text))` (tokens separated by one space, no
/// leading or trailing space or line end, integers without '+' or leading zeros, no "-0").
/// Otherwise nothing, and `why` (if given) says what is wrong: parse()'s reason, or the
/// canonical text expected. The ranges are parse()'s (docs/tello_sdk.md): up/down/left/right/
/// forward/back 20..500 cm; cw/ccw 1..360 deg; flip l r f b; go x y z in -500..500 not all
/// within -20..20, speed 10..100; curve coordinates -500..500, speed 10..60, arc radius
/// 0.5..10 m (the circle through the origin and both points); speed 10..100; rc four integers
/// in -100..100.
std::optional<CommandKind> classify_command(std::string_view text, std::string* why = nullptr);

/// "rc a b c d" for sticks already in range (asserted).
std::string rc_text(int a, int b, int c, int d);
/// True when the datagram's verb is `rc` (exactly "rc", or "rc " and its arguments), whether or
/// not its arguments parse: the Tello never answers an rc datagram, even a malformed one.
bool is_rc_text(std::string_view text);

/// A flying Tello that hears no command at all for this long lands by itself, s
/// (docs/tello_sdk.md): the simulated Tello's watchdog and the bound on tello_pilot's riding
/// through a link outage.
inline constexpr double kCommandWatchdog_s = 15.0;

/// How long to wait for a command's reply, s: the one table of reply timeouts, which the
/// driver, the flight software's configuration and tello_pilot's own landing take their
/// defaults from. Clients wait about 7 s (docs/tello_sdk.md); `takeoff` is answered once its
/// climb has ended, 20 s; `land` once the drone is down, and 10 s is the longest a landing
/// may take (from the highest cruise height at the Tello's descent speed, with its re-sends).
struct ReplyTimeouts {
  double default_s = 7.0;
  double takeoff_s = 20.0;
  double land_s = 10.0;
  /// takeoff_s for exactly "takeoff", land_s for exactly "land", default_s for any other text,
  /// in nanoseconds.
  TimeNs timeout_for(std::string_view text) const;
};

}  // namespace shelfcross::sdk
