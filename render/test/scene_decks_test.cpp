// The scene layout of a shelf with solid decks (warehouse.hpp): one board per cell floor in the
// bars' colour, the boxes and their markers standing on it; without decks, nothing changes.
#include <gtest/gtest.h>

#include "render/render_error.hpp"
#include "render/scene.hpp"
#include "render/test/test_warehouse.hpp"

namespace shelfcross::render {
namespace {

TEST(SceneLayout, SolidDecksAreBoardsUnderTheBoxes) {
  Warehouse w = test::paper_test_shelf();
  const SceneLayout open = build_scene_layout(w);
  w.shelves[0].deck_thickness_m = 0.018;
  const SceneLayout decked = build_scene_layout(w);
  ASSERT_EQ(decked.cuboids.size(), open.cuboids.size() + 4u);  // under levels 1 to 4
  // The decks follow the rails: the bars' cuboids before them are the same.
  const std::size_t bars = open.cuboids.size() - w.shelves[0].boxes.size();
  for (std::size_t i = 0; i < bars; ++i) {
    EXPECT_EQ(decked.cuboids[i].min_S_m, open.cuboids[i].min_S_m);
    EXPECT_EQ(decked.cuboids[i].max_S_m, open.cuboids[i].max_S_m);
  }
  // The deck under level 2: from the beam's top (0.64 + 0.01) up by 18 mm, through the depth
  // and across the shelf between the outer posts' centre lines (y_S 0.82 .. -0.82).
  const Cuboid& deck = decked.cuboids[bars + 1];
  EXPECT_EQ(deck.kind, Cuboid::Kind::kRail);
  EXPECT_NEAR(deck.min_S_m.z(), 0.65, 1e-12);
  EXPECT_NEAR(deck.max_S_m.z(), 0.668, 1e-12);
  EXPECT_NEAR(deck.min_S_m.x(), 0.0, 1e-12);
  EXPECT_NEAR(deck.max_S_m.x(), 0.34, 1e-12);
  EXPECT_NEAR(deck.min_S_m.y(), -0.82, 1e-12);
  EXPECT_NEAR(deck.max_S_m.y(), 0.82, 1e-12);
  // Every box and its markers rise by the deck's thickness.
  ASSERT_EQ(decked.markers.size(), open.markers.size());
  for (std::size_t i = 0; i < open.markers.size(); ++i) {
    EXPECT_NEAR(decked.markers[i].centre_W_m.z() - open.markers[i].centre_W_m.z(), 0.018, 1e-12);
  }
  // A deck so thick that a box no longer fits its cell is refused.
  w.shelves[0].deck_thickness_m = 0.11;
  EXPECT_THROW(build_scene_layout(w), RenderError);
}

}  // namespace
}  // namespace shelfcross::render
