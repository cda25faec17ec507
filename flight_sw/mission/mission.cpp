#include "flight_sw/mission/mission.hpp"

namespace shelfcross::flight_sw {

const char* outcome_name(Outcome o) {
  switch (o) {
    case Outcome::Running: return "running";
    case Outcome::Crossed: return "crossed";
    case Outcome::Completed: return "completed";
    case Outcome::NoEmptyCell: return "no_empty_cell";
    case Outcome::Aborted: return "aborted";
  }
  return "?";
}

}  // namespace shelfcross::flight_sw
