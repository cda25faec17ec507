#pragma once
// A cell of a shelf by its numbering, the value both the flight software (the cell it chose)
// and the ground truth (the cell the vehicle crossed) speak of.

namespace shelfcross {

/// A cell by its shelf numbering: level from the floor, column from the left, both from 1
/// (0 means none was set; a valid cell has 1 <= level <= levels, 1 <= column <= columns).
struct CellIndex {
  int level = 0;
  int column = 0;
  bool operator==(const CellIndex&) const = default;
};

}  // namespace shelfcross
