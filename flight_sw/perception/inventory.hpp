#pragma once
// The inventory of one shelf: which box (marker ID) sits in which cell, which cells are empty.
// Built from full-view frames: each frame that shows the whole front grid is one observation
// of every cell. A box counts once N frames (marker_min_agreeing_frames) have seen its ID in
// the same cell and no other ID has been seen there as often; a cell counts as empty once N
// whole views have seen it and no marker was ever seen in it (a flickering sighting leaves the
// cell "uncertain": never listed, never chosen as a target). A whole view of a cell is a whole
// frame, or a damaged one whose damaged rows (CameraFrame::damaged_rows) all lie clear of the
// cell's rows: what a damaged picture shows outside its damaged rows is what the whole picture
// would show there (the receiver's damage map, checked against a loss-free decode).
// Why only whole views vouch for "empty": in an error-concealed picture a band is guessed
// from an older one, and the damage lasts until the next key frame, so several frames in a row
// can miss the same marker. A marker they do decode is real (ArUco's code check rejects a
// smeared one), so damaged frames still vote for boxes.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "flight_sw/perception/shelf_view.hpp"

namespace shelfcross::flight_sw {

struct BoxEntry {
  int id = 0;
  int shelf = 0;   ///< shelf index in the mission, from 0
  int level = 0;   ///< from the floor, from 1
  int column = 0;  ///< from the left as seen on approach, from 1
  bool operator==(const BoxEntry&) const = default;
};

class Inventory {
 public:
  Inventory() = default;
  /// levels, columns and min_agreeing_frames must be >= 1 (asserted).
  Inventory(int shelf_index, int levels, int columns, int min_agreeing_frames);

  /// One full-view frame: the (cell, marker id) sightings it produced; `whole` is false for
  /// an error-concealed (damaged) picture.
  void observe(const std::vector<std::pair<CellIndex, int>>& sightings, bool whole = true);
  /// One damaged full-view frame whose view of the cells in `whole_cells` is whole (their
  /// rows clear of its damage). Every cell must be in the shelf's grid.
  void observe(const std::vector<std::pair<CellIndex, int>>& sightings, const std::vector<CellIndex>& whole_cells);

  int frames() const { return frames_; }
  /// Frames observed whole.
  int whole_frames() const { return whole_frames_; }
  /// Whole views of a cell: the only ones that count toward its being empty.
  int whole_views(CellIndex cell) const { return whole_views_[slot(cell)]; }
  /// Whether every cell without a decided box has enough whole views to be judged empty or not.
  bool empty_decidable() const;
  int levels() const { return levels_; }
  int columns() const { return columns_; }
  /// The box decided in a cell, if any.
  std::optional<int> box_at(CellIndex cell) const;
  /// Whether a cell is decided empty.
  bool is_empty(CellIndex cell) const;
  /// Decided boxes, ordered by level then column.
  std::vector<BoxEntry> boxes() const;
  /// Decided empty cells, ordered by level then column.
  std::vector<CellIndex> empty_cells() const;
  /// Cells neither decided a box nor empty.
  std::vector<CellIndex> uncertain_cells() const;

  /// {"shelf":0,"levels":4,"columns":4,"frames":5,"whole_frames":5,
  ///  "boxes":[{"id":7,"shelf":0,"level":1,"column":2},...],
  ///  "empty":[{"level":1,"column":1},...],"uncertain":[...]}
  std::string to_json() const;

 private:
  size_t slot(CellIndex cell) const;  ///< index into counts_
  int shelf_ = 0;
  int levels_ = 0;
  int columns_ = 0;
  int min_agreeing_ = 1;
  int frames_ = 0;
  int whole_frames_ = 0;
  std::vector<std::map<int, int>> counts_;  ///< per cell (row-major by level): id -> frames
  std::vector<int> whole_views_;            ///< per cell: whole views
};

}  // namespace shelfcross::flight_sw
