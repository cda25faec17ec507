#pragma once
// The Tello SDK's command text, parsed into typed commands with the SDK's range rules
// (shared/tello/PROTOCOL.md). One parser for the simulated firmware (plant::Autopilot), the
// `shelfcross plant` command files and the Tello emulator.
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

namespace shelfcross::plant::sdk {

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
/// verbs are case-sensitive lower case, as the firmware expects.
std::variant<Command, ParseError> parse(std::string_view text);

/// The verb as spelled on the wire ("takeoff", "battery?", ...).
std::string_view verb_text(Verb verb);
/// The canonical wire text of a command ("rc 0 50 0 0").
std::string to_text(const Command& command);

bool is_read(Verb verb);        ///< "...?" commands: answered at once with a value
bool is_manoeuvre(Verb verb);   ///< takeoff, land, moves, turns, flip, go, curve: deferred reply

}  // namespace shelfcross::plant::sdk
