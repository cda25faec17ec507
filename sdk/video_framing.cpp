#include "sdk/video_framing.hpp"

#include <cassert>
#include <cstdint>
#include <optional>

namespace shelfcross::sdk {
namespace {

// One NAL unit of an Annex-B string.
struct Nal {
  std::size_t code_begin;  ///< first byte of the start code (00 00 01 or 00 00 00 01)
  std::size_t payload;     ///< first byte of the NAL header
};

std::vector<Nal> find_nals(std::string_view s) {
  std::vector<Nal> nals;
  for (std::size_t i = 0; i + 3 <= s.size(); ++i) {
    if (s[i] == 0 && s[i + 1] == 0 && s[i + 2] == 1) {
      const std::size_t begin = (i > 0 && s[i - 1] == 0) ? i - 1 : i;
      nals.push_back({begin, i + 3});
      i += 2;
    }
  }
  return nals;
}

// Reads an unsigned Exp-Golomb code (ue(v), H.264 9.1) from the RBSP of `nal` starting at
// `byte` (emulation-prevention bytes 00 00 03 skipped). Nothing when the bytes run out first
// or the code is longer than 31 bits.
std::optional<int> read_ue(std::string_view nal, std::size_t byte) {
  int zeros_seen = 0;  // consecutive zero bytes, for the emulation-prevention rule
  std::uint32_t bits = 0;
  int nbits = 0;
  auto next_bit = [&]() -> std::optional<int> {
    if (nbits == 0) {
      for (;;) {
        if (byte >= nal.size()) return std::nullopt;
        const auto b = static_cast<unsigned char>(nal[byte++]);
        if (zeros_seen >= 2 && b == 3) {  // 00 00 03: the 03 is not data
          zeros_seen = 0;
          continue;
        }
        zeros_seen = b == 0 ? zeros_seen + 1 : 0;
        bits = b;
        nbits = 8;
        break;
      }
    }
    --nbits;
    return static_cast<int>((bits >> nbits) & 1u);
  };
  int leading = 0;
  for (;;) {
    const std::optional<int> b = next_bit();
    if (!b) return std::nullopt;
    if (*b == 1) break;
    if (++leading > 30) return std::nullopt;
  }
  std::uint32_t value = 0;
  for (int i = 0; i < leading; ++i) {
    const std::optional<int> b = next_bit();
    if (!b) return std::nullopt;
    value = (value << 1) | static_cast<std::uint32_t>(*b);
  }
  return static_cast<int>((1u << leading) - 1u + value);
}

}  // namespace

std::vector<SliceSpan> slice_spans(std::string_view s) {
  std::vector<SliceSpan> out;
  const std::vector<Nal> nals = find_nals(s);
  for (std::size_t i = 0; i < nals.size(); ++i) {
    if (nals[i].payload >= s.size()) continue;
    const int type = static_cast<unsigned char>(s[nals[i].payload]) & 0x1f;
    if (type != 1 && type != 5) continue;
    const std::size_t end = i + 1 < nals.size() ? nals[i + 1].code_begin : s.size();
    const std::optional<int> first_mb = read_ue(s.substr(0, end), nals[i].payload + 1);
    if (first_mb) out.push_back({*first_mb, nals[i].code_begin, end});
  }
  return out;
}

std::vector<int> nal_unit_types(std::string_view s) {
  std::vector<int> types;
  for (const Nal& n : find_nals(s)) {
    if (n.payload < s.size()) types.push_back(static_cast<unsigned char>(s[n.payload]) & 0x1f);
  }
  return types;
}

bool starts_with_start_code(std::string_view s) {
  return (s.size() >= 3 && s[0] == 0 && s[1] == 0 && s[2] == 1) ||
         (s.size() >= 4 && s[0] == 0 && s[1] == 0 && s[2] == 0 && s[3] == 1);
}

bool only_parameter_sets(std::string_view s) {
  if (!starts_with_start_code(s)) return false;
  const std::vector<int> types = nal_unit_types(s);
  for (int t : types) {
    if (t != 6 && t != 7 && t != 8 && t != 9) return false;
  }
  return !types.empty();
}

bool begins_access_unit(std::string_view s) {
  std::size_t header = 0;
  if (s.size() >= 4 && s[0] == 0 && s[1] == 0 && s[2] == 0 && s[3] == 1) {
    header = 4;
  } else if (s.size() >= 3 && s[0] == 0 && s[1] == 0 && s[2] == 1) {
    header = 3;
  } else {
    return false;
  }
  if (s.size() <= header) return false;
  const int type = static_cast<unsigned char>(s[header]) & 0x1f;
  if (type == 6 || type == 7 || type == 8 || type == 9) return true;
  if (type != 1 && type != 5) return false;
  return s.size() > header + 1 && (static_cast<unsigned char>(s[header + 1]) & 0x80) != 0;
}

std::vector<std::string> tello_datagrams(std::string_view au, std::size_t datagram_size) {
  assert(datagram_size >= 2);
  std::vector<std::string> out;
  const std::vector<Nal> nals = find_nals(au);
  std::size_t rest = 0;
  // Leading parameter sets (SPS 7, PPS 8, access unit delimiter 9): one datagram each.
  for (std::size_t i = 0; i < nals.size(); ++i) {
    const int type = nals[i].payload < au.size() ? (static_cast<unsigned char>(au[nals[i].payload]) & 0x1f) : 0;
    if (type != 7 && type != 8 && type != 9) break;
    const std::size_t end = i + 1 < nals.size() ? nals[i + 1].code_begin : au.size();
    if (end - nals[i].code_begin >= datagram_size) break;  // too big to stand alone as "short"
    out.emplace_back(au.substr(nals[i].code_begin, end - nals[i].code_begin));
    rest = end;
  }
  std::string_view body = au.substr(rest);
  while (body.size() > datagram_size) {
    out.emplace_back(body.substr(0, datagram_size));
    body.remove_prefix(datagram_size);
  }
  // The last datagram must be short: receivers end a frame at the first short one. An exact
  // multiple of the datagram size ends with an empty datagram (splitting it as size - 1 and 1
  // instead, as before, made the size - 1 piece end the frame a byte early: a damaged picture,
  // and its group of pictures, on a clean link).
  if (!body.empty()) out.emplace_back(body);
  if (body.size() == datagram_size) out.emplace_back();
  return out;
}

}  // namespace shelfcross::sdk
