#pragma once
// The Tello text SDK's commands as PROTOCOL.md lists them: which exist, their argument
// ranges, which move the drone, which get a reply and how long to wait for it. The driver
// validates every outgoing text here before it goes on the wire: a command out of range is
// refused locally (the drone would answer "out of range", or worse, act on it).

#include <optional>
#include <string>
#include <string_view>

#include "shelfcross/time.hpp"

namespace shelfcross::tello {

enum class CommandKind {
  Control,  ///< command, streamon, streamoff: session and video, no motion
  Read,     ///< battery?, height?, ...: answered with a value
  Motion,   ///< takeoff, land, emergency, stop, moves, turns, flip, go, curve, speed
  Rc,       ///< rc a b c d: never answered
};

/// The command's kind when `text` is a valid SDK 1.3/2.0 command in canonical form (tokens
/// separated by one space, integers without '+' or leading zeros beyond "0") with every
/// argument in range; otherwise nothing, and `why` (if given) says what is wrong.
/// Ranges: up/down/left/right/forward/back 20..500 cm; cw/ccw 1..360 deg; flip l r f b;
/// go x y z in -500..500 not all within -20..20, speed 10..100; curve coordinates -500..500,
/// speed 10..60, arc radius 0.5..10 m (the circle through the origin and both points); speed
/// 10..100; rc four integers in -100..100.
std::optional<CommandKind> classify_command(std::string_view text, std::string* why = nullptr);

/// "rc a b c d" for sticks already in range (asserted).
std::string rc_text(int a, int b, int c, int d);

/// How long to wait for a command's reply (PROTOCOL.md: about 7 s; 20 s for takeoff).
struct ReplyTimeouts {
  TimeNs default_ns = 7 * kNsPerSecond;
  TimeNs takeoff_ns = 20 * kNsPerSecond;
  TimeNs land_ns = 7 * kNsPerSecond;
  TimeNs timeout_for(std::string_view text) const;
};

}  // namespace shelfcross::tello
