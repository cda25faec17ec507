// The damage map's rules on hand-made evidence (picture_damage.hpp). The same map against
// the truth, on a real lossy libx264 stream: verification/cosim/test/picture_damage_test.cpp.
#include "flight_sw/tello/picture_damage.hpp"

#include <gtest/gtest.h>

namespace shelfcross::tello {
namespace {

using Ranges = std::vector<std::pair<int, int>>;
constexpr int kMbs = 60 * 45;  // 960 x 720

// One slice per macroblock row, `bytes` long each, after a 100-byte parameter-set datagram.
std::vector<sdk::SliceSpan> row_slices(int rows, std::size_t bytes) {
  std::vector<sdk::SliceSpan> s;
  for (int r = 0; r < rows; ++r) s.push_back({r * 60, 100 + r * bytes, 100 + (r + 1) * bytes});
  return s;
}

TEST(PictureDamage, SuspectsTheSlicesADatagramEndTouches) {
  // Slices of 500 bytes in 1460-byte datagrams: datagram ends at 100 (parameter sets), 1560,
  // 3020, ... The slices that hold a datagram end (or end on one) are suspect, with everything
  // up to the next slice that arrived.
  PictureEvidence e;
  e.lost = true;
  e.slices = row_slices(45, 500);
  e.datagram_ends = {100};
  for (std::size_t end = 1560; end < 100 + 45 * 500; end += 1460) e.datagram_ends.push_back(end);
  e.datagram_ends.push_back(100 + 45 * 500);
  const Ranges r = suspect_macroblocks(e, kMbs);
  // 1560 lies in slice 2 (1100..1600), 3020 in slice 5 (2600..3100), ...; the last slice ends
  // where the last datagram ended, and a datagram after it may be missing.
  ASSERT_GE(r.size(), 3u);
  EXPECT_EQ(r[0], std::make_pair(2 * 60, 3 * 60));
  EXPECT_EQ(r[1], std::make_pair(5 * 60, 6 * 60));
  EXPECT_EQ(r.back(), std::make_pair(43 * 60, kMbs));  // 22000 in slice 43, 22600 its end

  // Rows 10 to 12 lost with the datagram that held their starts: slice 9 swallows the gap.
  PictureEvidence gap;
  gap.lost = true;
  gap.slices = row_slices(45, 500);
  gap.slices.erase(gap.slices.begin() + 10, gap.slices.begin() + 13);
  gap.slices[9].end = gap.slices[10].begin;
  gap.datagram_ends = {100, gap.slices[9].begin + 200, 100 + 45 * 500};
  EXPECT_EQ(suspect_macroblocks(gap, kMbs), (Ranges{{9 * 60, 13 * 60}, {44 * 60, kMbs}}));
  // The first datagram lost: the rows before the first slice that arrived.
  PictureEvidence late;
  const std::vector<sdk::SliceSpan> all = row_slices(45, 500);
  late.slices.assign(all.begin() + 4, all.end());
  EXPECT_EQ(suspect_macroblocks(late, kMbs), (Ranges{{0, 4 * 60}}));
  // Slices out of order (two frames run together), or none: all of it.
  PictureEvidence swapped;
  swapped.slices = row_slices(3, 500);
  std::swap(swapped.slices[0].first_mb, swapped.slices[2].first_mb);
  EXPECT_EQ(suspect_macroblocks(swapped, kMbs), (Ranges{{0, kMbs}}));
  EXPECT_EQ(suspect_macroblocks(PictureEvidence{}, kMbs), (Ranges{{0, kMbs}}));
}

TEST(PictureDamage, PlacesTheLossByTheSliceLayoutWhereTheDecoderVouchesForTheRest) {
  // One slice per macroblock row (60 macroblocks), 500 bytes each, in 1460-byte datagrams; the
  // datagram that held the starts of rows 10 to 12 was lost, 200 bytes into row 9.
  PictureEvidence e;
  e.lost = true;
  e.slices = row_slices(45, 500);
  e.slices.erase(e.slices.begin() + 10, e.slices.begin() + 13);
  e.slices[9].end = e.slices[10].begin;
  for (std::size_t end = 1560; end < 100 + 42 * 500; end += 1460) e.datagram_ends.push_back(end);
  e.datagram_ends.push_back(100 + 42 * 500);
  e.concealed_mbs = 3 * 60 + 25;  // rows 10 to 12 and the tail of row 9
  e.error_mbs = {9 * 60 + 35};
  const Ranges by_datagrams = suspect_macroblocks(e, kMbs);
  EXPECT_GT(by_datagrams.size(), 5u) << "every slice across a boundary";
  // The gap after row 9 places the loss (row 9, the missing rows and row 13 after them); the
  // decoder concealed no more than that and failed only in it, so the slices across the other
  // boundaries are whole.
  EXPECT_EQ(suspect_macroblocks(e, kMbs, 60), (Ranges{{9 * 60, 14 * 60}}));
  // It concealed more (a slice that lost its middle ended early), or failed elsewhere: every
  // slice across a boundary is suspect again, with the gap.
  Ranges with_gap;
  for (const auto& r : by_datagrams) {
    if (r.second == 13 * 60) with_gap.push_back({r.first, 14 * 60});
    else if (r.first == 13 * 60 || r.first == 14 * 60) with_gap.back().second = r.second;
    else with_gap.push_back(r);
  }
  PictureEvidence more = e;
  more.concealed_mbs = 6 * 60;
  EXPECT_EQ(suspect_macroblocks(more, kMbs, 60), with_gap);
  PictureEvidence elsewhere = e;
  elsewhere.error_mbs.push_back(30 * 60 + 4);
  EXPECT_EQ(suspect_macroblocks(elsewhere, kMbs, 60), with_gap);
  // A slice that does not start on the layout: the layout is not this stream's.
  PictureEvidence off = e;
  off.slices[20].first_mb += 30;
  EXPECT_EQ(suspect_macroblocks(off, kMbs, 60), suspect_macroblocks(off, kMbs));
}

TEST(PictureDamage, LearnsTheSliceLayoutFromAWholePicture) {
  PictureEvidence lost;
  lost.lost = true;
  lost.slices = row_slices(45, 500);
  lost.slices.erase(lost.slices.begin() + 30);
  lost.slices[29].end = lost.slices[30].begin;
  lost.datagram_ends = {100, 100 + 29 * 500 + 100, 100 + 45 * 500};
  lost.concealed_mbs = 60;
  PictureEvidence whole;
  whole.slices = row_slices(45, 500);
  PictureDamage unknown(960, 720, 0), learnt(960, 720, 0);
  learnt.update(whole);
  // Without the layout, the last slice (it ends where the last datagram did) is suspect too.
  EXPECT_EQ(unknown.update(lost), (std::vector<RowSpan>{{29 * 16, 31 * 16}, {44 * 16, 720}}));
  EXPECT_EQ(learnt.update(lost), (std::vector<RowSpan>{{29 * 16, 32 * 16}}));  // and row 31 after the gap
}

TEST(PictureDamage, FollowsDamageAlongMotionVectorsUntilAWholeKeyFrame) {
  PictureDamage d(960, 720, 4);
  // Picture 1: row 20 lost (its slice held a datagram end).
  PictureEvidence lost;
  lost.lost = true;
  lost.slices = row_slices(45, 1000);
  lost.datagram_ends = {100, 100 + 20 * 1000 + 500};
  const std::vector<RowSpan> first = d.update(lost);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0], (RowSpan{20 * 16 - 4, 21 * 16 + 4}));

  // Picture 2: whole data; one block copies from 100 rows below the band (clean source), one
  // from the band itself, moving it up by 64 rows.
  PictureEvidence next;
  next.slices = row_slices(45, 1000);
  next.motion = {{16, 16, 8, 28, 4 * 100, 4},                  // source rows 120..136: clean
                 {16, 16, 200, 264, 4 * 64, 4}};               // source rows 320..336: damaged
  const std::vector<RowSpan> second = d.update(next);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0], (RowSpan{256, 272}));
  // An intra macroblock below the damaged block, in the same slice (one slice for rows 16 and
  // 17), inherits it; in another slice it would not.
  PictureEvidence intra = next;
  intra.slices = {{0, 100, 5000}};
  intra.motion = {{16, 16, 200, 264, 0, 4}};                   // row 16 copies itself: damaged
  const std::vector<RowSpan> third = d.update(intra);
  ASSERT_FALSE(third.empty());
  EXPECT_EQ(third[0].v_begin_px, 256);
  EXPECT_EQ(third[0].v_end_px, 720) << "every intra row below in the one slice inherits the damage";
  // An intra picture that arrived whole ends it all.
  PictureEvidence key;
  key.slices = row_slices(45, 1000);
  EXPECT_TRUE(d.update(key).empty());
  EXPECT_TRUE(d.update(next).empty()) << "the band was forgotten with the key frame";
}

TEST(PictureDamage, MarksTheRowsWhoseInterpolationWindowTouchesTheDamage) {
  PictureDamage d(960, 720, 0);
  // Slice 1 (macroblock row 20) held a datagram end: rows 320..336.
  PictureEvidence lost;
  lost.lost = true;
  lost.slices = {{0, 0, 10}, {20 * 60, 10, 20}, {21 * 60, 20, 30}};
  lost.datagram_ends = {15};
  ASSERT_EQ(d.update(lost), (std::vector<RowSpan>{{320, 336}}));
  // A block landing at rows 352..368 from 14 whole rows up: row v reads luma row v - 14 and
  // the chroma row of v - 14, all below the band.
  // Every macroblock of that row is inter: an intra one would take the whole row (rule 3).
  PictureEvidence moved;
  moved.slices = row_slices(45, 10);
  for (int col = 0; col < 60; ++col) moved.motion.push_back({16, 16, 8 + 16 * col, 360, -4 * 14, 4});
  PictureDamage copy = d;
  EXPECT_TRUE(copy.update(moved).empty());
  // A quarter pixel further up: the 6-tap filter reads rows floor(v - 14.25) - 2 ..
  // floor(v - 14.25) + 3, so row 352 reads 335, the band's last row; the rows below it, and
  // the chroma rows (336 and on), are clean.
  for (BlockMotion& b : moved.motion) b.motion_y = -4 * 14 - 1;
  EXPECT_EQ(d.update(moved), (std::vector<RowSpan>{{352, 353}}));
}

TEST(PictureDamage, RefusesAnEmptyPicture) {
  EXPECT_THROW(PictureDamage(0, 720), std::invalid_argument);
  EXPECT_THROW(PictureDamage(960, 720, -1), std::invalid_argument);
}

}  // namespace
}  // namespace shelfcross::tello
