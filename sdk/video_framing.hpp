#pragma once
// The Tello's video framing (docs/tello_sdk.md, Video): raw H.264 Annex-B on UDP port 11111, each
// access unit (one picture, with SPS and PPS before a key frame) cut into 1460-byte datagrams
// with a shorter last one, so a receiver finds a frame's end at its first short datagram. Both
// sides of the rule live here: tello_datagrams cuts (the drone's side, used by the simulated
// Tello in verification/), and the frame-boundary tests below are what the receiver
// (flight_sw/tello/video_receiver) reassembles by. Pure byte framing: no codec.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace shelfcross::sdk {

/// The Tello's video datagram size: every datagram of a frame but the last has this size.
inline constexpr std::size_t kVideoDatagramBytes = 1460;

/// The NAL unit types (nal_unit_type, 5 bits) of an Annex-B byte string, in order. Any bytes:
/// none without a start code, and a start code at the very end adds nothing.
std::vector<int> nal_unit_types(std::string_view annex_b);

/// True when `bytes` begins with an Annex-B start code (00 00 01 or 00 00 00 01).
bool starts_with_start_code(std::string_view bytes);

/// Parameter sets, delimiters and SEI only (NAL types 6 7 8 9, at least one), starting with a
/// start code: no picture yet. The Tello sends SPS and PPS as short datagrams of their own
/// before each key frame, so a short datagram holding only these does not end the frame.
bool only_parameter_sets(std::string_view bytes);

/// A datagram that begins an access unit: a start code, then an SPS, PPS, SEI or delimiter,
/// or a slice (NAL type 1 or 5) whose first_mb_in_slice is 0 (ue(v) 0 is the single bit 1
/// right after the one-byte NAL header). The Tello starts each frame in a datagram of its
/// own, and within a frame only its first slice begins at macroblock 0.
bool begins_access_unit(std::string_view datagram);

/// One coded slice of an access unit: where its NAL unit lies and where it begins in the
/// picture. A slice covers the macroblocks from first_mb (raster order) up to the next slice's.
struct SliceSpan {
  int first_mb = 0;         ///< first_mb_in_slice, the macroblock the slice begins at
  std::size_t begin = 0;    ///< offset of its start code in the access unit
  std::size_t end = 0;      ///< offset of the next NAL unit's start code, or the string's end
};

/// The coded slices (NAL types 1 and 5) of an Annex-B byte string, in byte order, with their
/// first_mb_in_slice (the slice header's first field, ue(v), read past emulation-prevention
/// bytes). A slice whose header is cut off before first_mb_in_slice ends is left out. Bytes
/// before the first start code (a frame that lost its first datagram) belong to no slice.
std::vector<SliceSpan> slice_spans(std::string_view annex_b);

/// The Tello's datagrams for one access unit: leading parameter sets (SPS, PPS, AUD) one per
/// datagram, then the rest cut into `datagram_size` pieces with a shorter last piece (when
/// the rest is an exact multiple, an empty datagram follows it), so a receiver finds the
/// frame's end at the first short datagram. `datagram_size` >= 2 (asserted).
std::vector<std::string> tello_datagrams(std::string_view access_unit,
                                         std::size_t datagram_size = kVideoDatagramBytes);

}  // namespace shelfcross::sdk
