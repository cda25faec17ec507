#include "verification/cosim/run_result.hpp"

namespace shelfcross::verification {

const char* outcome_name(RunOutcome outcome) {
  switch (outcome) {
    case RunOutcome::success: return "success";
    case RunOutcome::collision: return "collision";
    case RunOutcome::left_arena: return "left_arena";
    case RunOutcome::timeout: return "timeout";
    case RunOutcome::numerical_failure: return "numerical_failure";
    case RunOutcome::flight_software_exception: return "flight_software_exception";
    case RunOutcome::mission_aborted: return "mission_aborted";
    case RunOutcome::no_crossing: return "no_crossing";
    case RunOutcome::inventory_mismatch: return "inventory_mismatch";
  }
  return "unknown";
}

}  // namespace shelfcross::verification
