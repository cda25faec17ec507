#pragma once
// Where a damaged picture is damaged: the rows of each decoded picture that may differ from
// what the drone encoded, so that a decision can rest on a picture whose damage lies away
// from what the decision needs (CameraFrame::damaged_rows).
//
// The Tello's stream is cut blindly into 1460-byte datagrams, so a lost datagram takes the
// bytes of one or more slices with it. What the receiver still knows of an access unit: the
// slices whose start codes arrived (sdk::slice_spans: where each begins in the picture) and
// where each received datagram ended. Rows are damaged in three ways:
//   1. Lost in this picture (when it shows a sign of loss): the macroblocks before the first
//      slice that arrived, and every slice whose bytes may not all have arrived, up to the
//      next slice that did. Where that is:
//      - A slice followed by a missing slice start (a gap): the lost datagram took the starts
//        of the slices after it and, unless it began exactly at one, its own tail; and the
//        slice after the gap, which libavcodec's error resilience was seen to conceal as well
//        (the check against the truth, below, found it; its source does not say). Gaps are
//        seen where the stream keeps one slice layout (slices of one size in macroblocks,
//        learnt from the last whole picture; libx264 with a fixed slice count, as the Tello
//        and its simulation encode): every slice that arrived must start on it.
//      - A slice that holds a datagram boundary (a received datagram ends inside it or at
//        its end) with no gap after it: a whole datagram may have been lost inside it. The
//        decoder vouches for these when it reported no failure outside the gaps and
//        concealed no more macroblocks than the gaps hold: a slice that lost its middle
//        decodes the bytes of a later datagram as its own and fails, or ends early or late,
//        which leaves macroblocks concealed. Otherwise, or without a known layout, they are
//        suspect.
//      The concealment then smooths each edge between a concealed and a decoded 8 x 8 block
//      (libavcodec's error resilience, FF_EC_DEBLOCK), 4 sample rows on each side: 4 picture
//      rows of luma and 4 chroma rows, 8 picture rows, of chroma (`concealment_reach_px`).
//   2. Predicted from damage: a row of an inter block (the decoder's exported motion vectors,
//      a block's destination and its source in a reference picture) is damaged when the rows
//      it is interpolated from touch a damaged row of any picture it may reference (the last
//      `refs` pictures: the exported vectors do not say which reference each uses). Row v of a
//      block moved by m rows reads luma row v + m, or rows floor(v + m) - 2 .. floor(v + m) + 3
//      when m is fractional (the 6-tap filter, H.264 8.4.2.2.1); its chroma (4:2:0: one chroma
//      row per pair of picture rows, the vector halved) is chroma row floor(v / 2 + m / 2) and,
//      when that is fractional, the next one (the bilinear filter). A chroma row counts as
//      damaged when either of its picture rows is.
//   3. Intra-predicted from damage: an intra macroblock (no motion vector) in a macroblock
//      row that holds a damaged row (its left neighbour, or its own upper rows, may be
//      damaged: the mask does not say which columns) or below a damaged row of its own
//      slice damages its whole macroblock row.
// The in-loop deblocking filter of a stream that uses it moves up to 3 rows of an undamaged
// neighbour towards a damaged block by a clipped amount; that low-amplitude bleed is not
// followed (following it would spread a band by a macroblock row per picture). The
// simulated Tello's stream does not deblock, and there the rows outside the damage are
// byte-identical to a loss-free decode (verification/cosim/test/picture_damage_test.cpp, at 1, 3
// and 5 % datagram loss). Two parts of rule 1 rest on that check rather than on a proof: the
// decoder's vouching (a slice that lost a whole datagram and still decoded to exactly its
// macroblocks with no report would escape it) and the slice after a gap.

#include <cstddef>
#include <deque>
#include <vector>

#include "sdk/video_framing.hpp"
#include "shelfcross/camera.hpp"

namespace shelfcross::tello {

/// One inter-predicted block of a picture, luma pixels: where it lands and where it comes
/// from in its reference picture (centres, as libavcodec exports them).
struct BlockMotion {
  int width_px = 16;
  int height_px = 16;
  int dst_centre_x_px = 0;
  int dst_centre_y_px = 0;
  int motion_y = 0;        ///< vertical motion vector, in 1 / motion_scale pixels
  int motion_scale = 4;    ///< H.264: quarter pixels
};

/// What is known of one decoded picture and the access unit it came from.
struct PictureEvidence {
  bool lost = false;                        ///< a sign of loss in this access unit
  bool unplaced = false;                    ///< damage nothing here can place (a picture lost before it)
  std::vector<int> error_mbs;               ///< macroblocks where the decoder reported a slice failing
  int concealed_mbs = 0;                    ///< macroblocks the decoder reported concealing
  std::vector<sdk::SliceSpan> slices;       ///< its slices that arrived, byte order
  std::vector<std::size_t> datagram_ends;   ///< offsets where each received datagram ended
  std::vector<BlockMotion> motion;          ///< its inter blocks (empty for intra pictures)
  int refs = 1;                             ///< reference pictures the stream may use (SPS)
};

/// Macroblock ranges [first, end) of a picture of `macroblocks` that may be lost from an access
/// unit with a sign of loss (rule 1 above), for a stream whose slices are `slice_mbs`
/// macroblocks each (0: not known). Slices out of raster order, or none at all: the whole
/// picture.
std::vector<std::pair<int, int>> suspect_macroblocks(const PictureEvidence& e, int macroblocks, int slice_mbs = 0);

/// Follows the damage of one stream picture by picture. Not thread-safe; one per decoder.
class PictureDamage {
 public:
  /// A picture of width x height pixels (both > 0; throws std::invalid_argument otherwise).
  PictureDamage(int width_px, int height_px, int concealment_reach_px = 8);
  /// The next decoded picture: returns its damaged rows (disjoint, top down; empty: whole).
  std::vector<RowSpan> update(const PictureEvidence& e);
  /// Forgets all damage (a new stream).
  void reset() {
    history_.clear();
    slice_mbs_ = 0;
  }

 private:
  int width_px_, height_px_, mb_cols_, mb_rows_, reach_px_;
  void learn_layout(const std::vector<sdk::SliceSpan>& slices);
  int slice_mbs_ = 0;  ///< the stream's slice layout, from the last whole picture (0: not known)
  std::deque<std::vector<std::uint8_t>> history_;  ///< row masks, newest first
};

}  // namespace shelfcross::tello
