// The mission's transition table: the paths the mission flies are in it, nothing else is.
#include <gtest/gtest.h>

#include <vector>

#include "flight_sw/mission/phases.hpp"

namespace shelfcross::flight_sw {
namespace {

constexpr Phase kAll[] = {Phase::Idle,          Phase::EnterSdk,      Phase::StartVideo, Phase::WaitVideo, Phase::TakeOff,
                          Phase::FindShelf,     Phase::GoToViewpoint, Phase::TakeInventory, Phase::Approach, Phase::Cross,
                          Phase::Transfer,      Phase::Land,          Phase::Done};

TEST(MissionPhases, TheNominalCrossingIsOnePathThroughTheTable) {
  const std::vector<Phase> path = {Phase::Idle,      Phase::EnterSdk,      Phase::StartVideo,    Phase::WaitVideo,
                                   Phase::TakeOff,   Phase::FindShelf,     Phase::GoToViewpoint, Phase::TakeInventory,
                                   Phase::Approach,  Phase::Cross,         Phase::Land,          Phase::Done};
  for (size_t i = 1; i < path.size(); ++i) {
    EXPECT_TRUE(may_enter(path[i - 1], path[i])) << phase_name(path[i - 1]) << " -> " << phase_name(path[i]);
  }
  // Several shelves and the conventional strategies; a drift seen in the crossing; a re-read.
  EXPECT_TRUE(may_enter(Phase::Cross, Phase::FindShelf));
  EXPECT_TRUE(may_enter(Phase::TakeInventory, Phase::Transfer));
  EXPECT_TRUE(may_enter(Phase::Transfer, Phase::FindShelf));
  EXPECT_TRUE(may_enter(Phase::Cross, Phase::Approach));
  EXPECT_TRUE(may_enter(Phase::Approach, Phase::FindShelf));
  EXPECT_TRUE(may_enter(Phase::GoToViewpoint, Phase::FindShelf));
  EXPECT_TRUE(may_enter(Phase::TakeInventory, Phase::FindShelf));  // the hover drifted off the view
}

TEST(MissionPhases, TheAirLeavesOnlyThroughLandAndTheGroundOnlyThroughDone) {
  for (Phase from : kAll) {
    EXPECT_EQ(may_enter(from, Phase::Land), airborne(from)) << phase_name(from);
    if (airborne(from)) {
      EXPECT_FALSE(may_enter(from, Phase::Done)) << phase_name(from);
    }
    EXPECT_FALSE(may_enter(Phase::Done, from)) << phase_name(from);
    EXPECT_FALSE(may_enter(from, Phase::Idle)) << phase_name(from);
    EXPECT_FALSE(may_enter(from, from)) << phase_name(from);
  }
  EXPECT_TRUE(may_enter(Phase::Land, Phase::Done));
  EXPECT_FALSE(may_enter(Phase::Land, Phase::FindShelf));  // no take-off again after a landing
  EXPECT_FALSE(may_enter(Phase::TakeInventory, Phase::Cross));  // no crossing without an approach
  EXPECT_FALSE(may_enter(Phase::FindShelf, Phase::Approach));   // nor an approach without an inventory
}

TEST(MissionPhases, VisionPhasesAreTheAirbornePhasesThatSteerOnPictures) {
  for (Phase p : kAll) {
    EXPECT_EQ(vision_phase(p), airborne(p) && p != Phase::Cross && p != Phase::Transfer) << phase_name(p);
  }
  EXPECT_TRUE(vision_phase(Phase::Approach));
  EXPECT_FALSE(airborne(Phase::Land));
  EXPECT_FALSE(airborne(Phase::TakeOff));
}

}  // namespace
}  // namespace shelfcross::flight_sw
