// The Tello's video framing on hand-made Annex-B bytes: the cutter (drone's side) and the
// frame-boundary rules the receiver uses, and that the two agree. The same rules on a real
// libx264 stream: flight_sw/tello/test/video_receiver_test.cpp.

#include "sdk/video_framing.hpp"

#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

namespace shelfcross::sdk {
namespace {

// A NAL unit with a 4-byte start code: header byte (nal_ref_idc 3, type), then payload.
std::string nal(int type, std::string payload) {
  std::string s("\0\0\0\1", 4);
  s += static_cast<char>(0x60 | type);
  return s + payload;
}

// A slice payload whose first_mb_in_slice is 0 (ue(v) '1') or not ('010' = 1).
std::string slice_payload(bool first_mb_zero, std::size_t size) {
  std::string p(size, '\x55');
  p[0] = first_mb_zero ? '\x88' : '\x48';
  return p;
}

TEST(SdkVideoFraming, NalUnitTypes) {
  const std::string au = nal(7, "\x42\xc0\x1f") + nal(8, "\xce\x38\x80") + nal(5, slice_payload(true, 40));
  EXPECT_EQ(nal_unit_types(au), (std::vector<int>{7, 8, 5}));
  EXPECT_EQ(nal_unit_types(std::string("\0\0\1\x41\x9a", 5)), std::vector<int>{1});  // 3-byte start code
  EXPECT_TRUE(nal_unit_types("no start code").empty());
}

TEST(SdkVideoFraming, FrameBoundaryRules) {
  EXPECT_TRUE(starts_with_start_code(std::string("\0\0\1\x67", 4)));
  EXPECT_TRUE(starts_with_start_code(std::string("\0\0\0\1\x67", 5)));
  EXPECT_FALSE(starts_with_start_code(std::string("\0\1\x67", 3)));
  EXPECT_FALSE(starts_with_start_code(""));

  EXPECT_TRUE(only_parameter_sets(nal(7, "\x42") + nal(8, "\xce")));
  EXPECT_TRUE(only_parameter_sets(nal(6, "\x05") + nal(9, "\xf0")));
  EXPECT_FALSE(only_parameter_sets(nal(7, "\x42") + nal(5, slice_payload(true, 8))));
  EXPECT_FALSE(only_parameter_sets(slice_payload(true, 8)));  // no start code

  for (int type : {6, 7, 8, 9}) EXPECT_TRUE(begins_access_unit(nal(type, "\x01"))) << type;
  EXPECT_TRUE(begins_access_unit(nal(5, slice_payload(true, 8))));
  EXPECT_TRUE(begins_access_unit(nal(1, slice_payload(true, 8))));
  EXPECT_FALSE(begins_access_unit(nal(1, slice_payload(false, 8))));  // a later slice of a frame
  EXPECT_FALSE(begins_access_unit(nal(1, "")));                       // header only
  EXPECT_FALSE(begins_access_unit(nal(2, slice_payload(true, 8))));   // data partition
  EXPECT_FALSE(begins_access_unit(slice_payload(true, 8)));           // the middle of a frame
}

// The RBSP bytes of ue(v) `value` followed by '1' bits, with emulation-prevention bytes.
std::string ue_payload(std::uint32_t value, std::size_t size) {
  std::vector<int> bits;
  const std::uint64_t code = static_cast<std::uint64_t>(value) + 1;
  int len = 0;
  while ((code >> (len + 1)) != 0) ++len;
  for (int i = 0; i < len; ++i) bits.push_back(0);
  for (int i = len; i >= 0; --i) bits.push_back(static_cast<int>((code >> i) & 1));
  while (bits.size() < size * 8) bits.push_back(1);
  std::string rbsp;
  for (std::size_t i = 0; i + 8 <= bits.size(); i += 8) {
    int b = 0;
    for (int k = 0; k < 8; ++k) b = (b << 1) | bits[i + k];
    rbsp += static_cast<char>(b);
  }
  std::string out;
  int zeros = 0;
  for (char c : rbsp) {
    const auto b = static_cast<unsigned char>(c);
    if (zeros >= 2 && b <= 3) {
      out += '\x03';
      zeros = 0;
    }
    out += c;
    zeros = b == 0 ? zeros + 1 : 0;
  }
  return out;
}

TEST(SdkVideoFraming, SliceSpansReadFirstMacroblock) {
  const std::string sps = nal(7, "\x42\xc0\x1f");
  const std::string s0 = nal(5, ue_payload(0, 30)), s1 = nal(5, ue_payload(60, 30)),
                    s2 = nal(5, ue_payload(3599, 30));
  const std::string au = sps + s0 + s1 + s2;
  const std::vector<SliceSpan> spans = slice_spans(au);
  ASSERT_EQ(spans.size(), 3u);
  EXPECT_EQ(spans[0].first_mb, 0);
  EXPECT_EQ(spans[1].first_mb, 60);
  EXPECT_EQ(spans[2].first_mb, 3599);
  EXPECT_EQ(spans[0].begin, sps.size());
  EXPECT_EQ(spans[0].end, sps.size() + s0.size());
  EXPECT_EQ(spans[2].end, au.size());
  // 23 leading zero bits put 00 00 01 in the RBSP: the writer inserts 03, the reader skips it.
  const std::uint32_t big = (1u << 23) + 12345u;
  const std::string escaped = nal(1, ue_payload(big, 12));
  ASSERT_NE(escaped.find(std::string("\0\0\3", 3), 5), std::string::npos);
  ASSERT_EQ(slice_spans(escaped).size(), 1u);
  EXPECT_EQ(slice_spans(escaped)[0].first_mb, static_cast<int>(big));
  // Bytes before the first start code (a lost first datagram) and a header cut short.
  EXPECT_EQ(slice_spans(ue_payload(5, 20) + s1).size(), 1u);
  EXPECT_TRUE(slice_spans(nal(1, std::string(2, '\0'))).empty());
  EXPECT_TRUE(slice_spans(sps).empty());
}

TEST(SdkVideoFraming, TelloDatagramsCutAsTheTelloDoes) {
  const std::string sps = nal(7, "\x42\xc0\x1f"), pps = nal(8, "\xce\x38\x80");
  const std::string slices = nal(5, slice_payload(true, 3000)) + nal(5, slice_payload(false, 1000));
  const std::string au = sps + pps + slices;
  const auto d = tello_datagrams(au);
  ASSERT_EQ(d.size(), 2u + (slices.size() + kVideoDatagramBytes - 1) / kVideoDatagramBytes);
  EXPECT_EQ(d[0], sps);
  EXPECT_EQ(d[1], pps);
  std::string joined;
  for (const auto& g : d) joined += g;
  EXPECT_EQ(joined, au);  // nothing added, nothing lost
  for (std::size_t i = 2; i + 1 < d.size(); ++i) EXPECT_EQ(d[i].size(), kVideoDatagramBytes) << i;
  EXPECT_LT(d.back().size(), kVideoDatagramBytes);

  // The receiver's reading of the cut: a frame begins at the first datagram after the
  // parameter sets, later datagrams do not begin one, and only the last is short.
  EXPECT_TRUE(only_parameter_sets(d[0]));
  EXPECT_TRUE(only_parameter_sets(d[1]));
  EXPECT_TRUE(begins_access_unit(d[2]));
  EXPECT_FALSE(only_parameter_sets(d[2]));
  for (std::size_t i = 3; i < d.size(); ++i) EXPECT_FALSE(begins_access_unit(d[i])) << i;

  // An exact multiple of the datagram size: full datagrams, then an empty one, so that the
  // first short datagram is the frame's last.
  const std::string exact = nal(1, slice_payload(true, 2 * 100 - 5));
  ASSERT_EQ(exact.size(), 200u);
  const auto e = tello_datagrams(exact, 100);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].size(), 100u);
  EXPECT_EQ(e[1].size(), 100u);
  EXPECT_EQ(e[2].size(), 0u);
}

}  // namespace
}  // namespace shelfcross::sdk
