// Inventory: boxes of a drawn shelf in known cells, levels and columns numbered from the floor
// and the left; a box on the shelf behind seen through an empty cell is not counted; votes.
// The survey's re-read from close: the shelf behind, whole through a cell, is not taken.

#include <gtest/gtest.h>

#include "flight_sw/mission/shelf_survey.hpp"
#include "flight_sw/mission/telemetry.hpp"
#include "flight_sw/perception/inventory.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/test/shelf_drawing.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {
namespace {


TEST(Inventory, DrawnShelfWithBoxesInKnownCellsIsExact) {
  testing::Scene scene;
  testing::DrawnShelf front = testing::paper_shelf({3.0, 0.0, 0.0});
  front.boxes = {{1, 2, 7}, {2, 4, 3}, {3, 1, 12}, {4, 3, 25}, {1, 4, 0}};
  testing::DrawnShelf behind = testing::paper_shelf({5.6, 0.0, 0.0});
  // Behind the empty front cell (level 2, column 2): must not be listed.
  behind.boxes = {{2, 2, 41}, {3, 3, 33}};
  scene.shelves = {front, behind};
  FlightConfig config;
  TagDetector tags(config.perception);
  MarkerDetector markers(config.shelf.aruco_dictionary);
  Inventory inv(0, 4, 4, config.perception.marker_min_agreeing_frames);
  const testing::Drawer drawer(config.camera, true);
  // Three frames hovering near the optimal viewpoint (2.1 m), slightly different each.
  const std::vector<Eigen::Vector4d> poses = {{0.85, 0.0, 0.98, 0.0}, {0.88, 0.04, 0.96, 2.0},
                                              {0.83, -0.03, 1.0, -1.5}};
  for (const auto& p : poses) {
    const cv::Mat img = drawer.draw(scene, testing::camera_pose_W(p.head<3>(), deg_to_rad(p[3])));
    ShelfView view;
    analyse_shelf(img, tags, config, view);
    ASSERT_TRUE(view.full) << view.grid.refusal;
    std::vector<MarkerSighting> seen;
    markers.detect(img, seen);
    ASSERT_GE(seen.size(), 5u);  // the front boxes at least; behind ones may show too
    inv.observe(assign_markers(view, seen, config));
  }
  const std::vector<BoxEntry> expected = {{7, 0, 1, 2}, {0, 0, 1, 4}, {3, 0, 2, 4}, {12, 0, 3, 1}, {25, 0, 4, 3}};
  EXPECT_EQ(inv.boxes(), expected);
  EXPECT_EQ(inv.empty_cells().size(), 11u);
  EXPECT_TRUE(inv.is_empty({2, 2}));
  EXPECT_TRUE(inv.uncertain_cells().empty());
  EXPECT_EQ(inv.to_json(),
            "{\"shelf\":0,\"levels\":4,\"columns\":4,\"frames\":3,\"whole_frames\":3,\"boxes\":["
            "{\"id\":7,\"shelf\":0,\"level\":1,\"column\":2},{\"id\":0,\"shelf\":0,\"level\":1,\"column\":4},"
            "{\"id\":3,\"shelf\":0,\"level\":2,\"column\":4},{\"id\":12,\"shelf\":0,\"level\":3,\"column\":1},"
            "{\"id\":25,\"shelf\":0,\"level\":4,\"column\":3}],\"empty\":["
            "{\"level\":1,\"column\":1},{\"level\":1,\"column\":3},{\"level\":2,\"column\":1},"
            "{\"level\":2,\"column\":2},{\"level\":2,\"column\":3},{\"level\":3,\"column\":2},"
            "{\"level\":3,\"column\":3},{\"level\":3,\"column\":4},{\"level\":4,\"column\":1},"
            "{\"level\":4,\"column\":2},{\"level\":4,\"column\":4}],\"uncertain\":[]}");
}

TEST(Inventory, MarkersMustAgreeOverNFrames) {
  Inventory inv(0, 2, 2, 3);
  // Cell (1,1): ID 5 three times -> a box. Cell (1,2): ID 6 twice -> uncertain.
  // Cell (2,1): ID 8 three times and ID 9 three times -> disagreement, uncertain.
  for (int f = 0; f < 3; ++f) {
    std::vector<std::pair<CellIndex, int>> s = {{{1, 1}, 5}, {{2, 1}, 8}, {{2, 1}, 9}};
    if (f < 2) s.push_back({{1, 2}, 6});
    inv.observe(s);
  }
  EXPECT_EQ(inv.box_at({1, 1}), 5);
  EXPECT_FALSE(inv.box_at({1, 2}));
  EXPECT_FALSE(inv.is_empty({1, 2}));
  EXPECT_FALSE(inv.box_at({2, 1}));
  EXPECT_TRUE(inv.is_empty({2, 2}));
  EXPECT_EQ(inv.uncertain_cells(), (std::vector<CellIndex>{{1, 2}, {2, 1}}));
  // Before N frames nothing is decided.
  Inventory early(0, 1, 1, 3);
  early.observe({});
  EXPECT_FALSE(early.is_empty({1, 1}));
}

// Error-concealed frames: the band holding a marker may be guessed in every frame until the
// next key frame, so damaged frames never vouch for an empty cell; a marker they decode is
// real and counts for its box.
TEST(Inventory, DamagedFramesVoteForBoxesButNeverForEmpty) {
  Inventory inv(0, 1, 2, 3);
  // Cell (1,1) holds box 5, but three damaged frames in a row missed it; cell (1,2) is empty.
  for (int f = 0; f < 3; ++f) inv.observe({}, /*whole=*/false);
  EXPECT_EQ(inv.frames(), 3);
  EXPECT_EQ(inv.whole_frames(), 0);
  EXPECT_FALSE(inv.empty_decidable());
  EXPECT_FALSE(inv.is_empty({1, 1})) << "damaged frames that missed a marker declared its cell empty";
  EXPECT_FALSE(inv.is_empty({1, 2}));
  EXPECT_EQ(inv.uncertain_cells().size(), 2u);
  // Damaged frames that do read the marker count toward the box.
  inv.observe({{{1, 1}, 5}}, false);
  inv.observe({{{1, 1}, 5}}, false);
  EXPECT_FALSE(inv.box_at({1, 1}));
  inv.observe({{{1, 1}, 5}}, false);
  EXPECT_EQ(inv.box_at({1, 1}), 5);
  // Whole frames decide the empty cell once there are N of them.
  inv.observe({{{1, 1}, 5}}, true);
  inv.observe({}, true);
  EXPECT_FALSE(inv.is_empty({1, 2}));
  inv.observe({{{1, 1}, 5}}, true);
  EXPECT_TRUE(inv.is_empty({1, 2}));
  EXPECT_FALSE(inv.is_empty({1, 1}));
  EXPECT_EQ(inv.whole_frames(), 3);
  EXPECT_EQ(inv.frames(), 9);
}

// A damaged frame whose damage lies clear of a cell's rows is a whole view of that cell: three
// such views decide an empty cell, while the cell under the damage stays undecided; the
// inventory can close once every cell without a box has its whole views.
TEST(Inventory, DamagedFramesViewCellsClearOfTheirDamageWhole) {
  Inventory inv(0, 2, 1, 3);  // cell (1,1) below, (2,1) above
  for (int f = 0; f < 3; ++f) inv.observe({}, std::vector<CellIndex>{{2, 1}});  // damage over the lower level
  EXPECT_EQ(inv.whole_frames(), 0);
  EXPECT_EQ(inv.whole_views({2, 1}), 3);
  EXPECT_EQ(inv.whole_views({1, 1}), 0);
  EXPECT_TRUE(inv.is_empty({2, 1}));
  EXPECT_FALSE(inv.is_empty({1, 1})) << "a cell under the damage was declared empty";
  EXPECT_FALSE(inv.empty_decidable());
  // The lower cell's box, read on damaged frames: every cell is now judged.
  for (int f = 0; f < 3; ++f) inv.observe({{{1, 1}, 8}}, std::vector<CellIndex>{{2, 1}});
  EXPECT_EQ(inv.box_at({1, 1}), 8);
  EXPECT_TRUE(inv.empty_decidable());
  EXPECT_EQ(inv.empty_cells(), (std::vector<CellIndex>{{2, 1}}));
}

// A re-read from close to the shelf (the target lost 0.4 m in front of cell L2 C2): through
// that empty cell the camera sees the whole next shelf, which FindShelf would take for the
// shelf being re-read (its viewpoint lies beyond the cell). Backing out, it is not taken.
TEST(ShelfSurvey, ReReadFromCloseBacksOutPastTheNextShelfSeenThroughTheCell) {
  testing::Scene scene;
  const testing::DrawnShelf front = testing::paper_shelf({3.0, 0.0, 0.0});
  testing::DrawnShelf behind = testing::paper_shelf({7.2, 0.0, 0.0});
  behind.boxes = {{1, 3, 28}};
  scene.shelves = {front, behind};
  FlightConfig config;
  const testing::Drawer drawer(config.camera, true);
  const double y = 0.5 * (testing::post_y(front, 1) + testing::post_y(front, 2));
  const double z = 0.5 * (testing::beam_z(front, 1) + testing::beam_z(front, 2));
  const cv::Mat img = drawer.draw(scene, testing::camera_pose_W({2.60, y, z}, 0.0));
  const Picture pic{img, 0, 0, true, nullptr};
  Telemetry telemetry;
  ShelfSurvey looking(config);
  // The hazard: the next shelf, whole through the cell, taken for the one being re-read.
  EXPECT_EQ(looking.find_shelf(pic, false, telemetry).next, SurveyStep::Next::WholeShelfInView)
      << telemetry.view.tags.size() << " tags, grid " << telemetry.view.grid_rows << " x "
      << telemetry.view.grid_columns << ": " << telemetry.view.grid_refusal;
  ShelfSurvey backing(config);
  const SurveyStep step = backing.find_shelf(pic, true, telemetry);
  EXPECT_EQ(step.next, SurveyStep::Next::Stay);
  ASSERT_TRUE(step.velocity);
  EXPECT_DOUBLE_EQ(step.velocity->vx_B_mps, -config.control.back_off_speed_mps);
  EXPECT_DOUBLE_EQ(step.velocity->yaw_rate_radps, 0.0);
}

}  // namespace
}  // namespace shelfcross::flight_sw
