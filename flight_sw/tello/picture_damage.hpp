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
//      next slice that did. A slice is trusted only if it lies inside one received datagram
//      and does not end where a datagram ended (a datagram that followed may be missing, with
//      the rest of the slice or the starts of the slices it carried). The decoder's own error
//      reports do not place the damage: a slice that lost its tail and ran on into the bytes
//      of a later datagram may decode to wrong pixels without any error, which the check
//      against the truth found. The concealment deblocks the concealed edges, which reaches a
//      few rows past them (`concealment_reach_px`).
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
// byte-identical to a loss-free decode (verification/test/picture_damage_test.cpp).

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
  std::vector<sdk::SliceSpan> slices;       ///< its slices that arrived, byte order
  std::vector<std::size_t> datagram_ends;   ///< offsets where each received datagram ended
  std::vector<BlockMotion> motion;          ///< its inter blocks (empty for intra pictures)
  int refs = 1;                             ///< reference pictures the stream may use (SPS)
};

/// Macroblock ranges [first, end) of a picture of `macroblocks` that may be lost from an access
/// unit with a sign of loss (rule 1 above). Slices out of raster order, or none at all: the
/// whole picture.
std::vector<std::pair<int, int>> suspect_macroblocks(const PictureEvidence& e, int macroblocks);

/// Follows the damage of one stream picture by picture. Not thread-safe; one per decoder.
class PictureDamage {
 public:
  /// A picture of width x height pixels (both > 0; std::invalid_argument otherwise).
  PictureDamage(int width_px, int height_px, int concealment_reach_px = 4);
  /// The next decoded picture: returns its damaged rows (disjoint, top down; empty: whole).
  std::vector<RowSpan> update(const PictureEvidence& e);
  /// Forgets all damage (a new stream).
  void reset() { history_.clear(); }

 private:
  int width_px_, height_px_, mb_cols_, mb_rows_, reach_px_;
  std::deque<std::vector<std::uint8_t>> history_;  ///< row masks, newest first
};

}  // namespace shelfcross::tello
