#include "plant/collision.hpp"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace shelfcross::plant {
namespace {

// The paper's test shelf (docs/method.md Table 3), 3 m ahead of the origin, facing it.
// post_y: 0.82, 0.48, 0.00, -0.34, -0.82; beam_z: 0.30, 0.64, 0.98, 1.32, 1.66.
Warehouse test_warehouse() {
  Warehouse w;
  ShelfSpec s;
  s.name = "test";
  s.origin_W_m = {3.0, 0.0, 0.0};
  s.column_pitch_m = {0.34, 0.48, 0.34, 0.48};
  s.row_pitch_m = {0.34, 0.34, 0.34, 0.34};
  s.base_height_m = 0.30;
  s.depth_m = 0.34;
  s.boxes = {{1, 1, 3}, {2, 3, 7}, {3, 4, 12}};
  w.shelves.push_back(s);
  w.box_size_m = {0.22, 0.22, 0.22};
  return w;
}

const Eigen::Vector3d kTello(0.098, 0.0925, 0.041);
constexpr double kMargin = 0.01;
constexpr TimeNs kStepNs = 2'000'000;  // the plant's 2 ms step

Eigen::Isometry3d pose(const Eigen::Vector3d& p, double yaw_rad = 0.0) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = p;
  return X;
}

// Flies straight from a toward b at speed_mps in plant steps (the last one may overshoot b),
// sweeping each step; the first contact.
std::optional<Contact> fly(const CollisionWorld& world, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, double speed_mps, TimeNs step_ns = kStepNs,
                           FloorContacts floor = FloorContacts::report) {
  const Eigen::Vector3d u = (b - a).normalized();
  const auto at = [&](TimeNs t_ns) { return pose(a + speed_mps * ns_to_seconds(t_ns) * u); };
  for (TimeNs t = 0; speed_mps * ns_to_seconds(t) < (b - a).norm(); t += step_ns) {
    if (auto c = world.sweep(at(t), t, at(t + step_ns), t + step_ns, floor)) return c;
  }
  return std::nullopt;
}

const Element& element_named(const CollisionWorld& world, const std::string& name) {
  for (const Element& e : world.elements()) {
    if (e.name == name) return e;
  }
  throw std::runtime_error("no element named " + name);
}

TEST(CollisionWorld, BuildsEveryNamedElement) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // floor + 4 walls + ceiling; per face 5 posts + 5 beams; 25 rails; 2 x 25 tags; 3 boxes.
  EXPECT_EQ(world.elements().size(), 6u + 20u + 25u + 50u + 3u);
  for (size_t i = 0; i < world.elements().size(); ++i) {
    EXPECT_EQ(world.elements()[i].id, static_cast<int>(i));
  }
  EXPECT_EQ(world.elements()[0].name, "floor");
  EXPECT_EQ(world.elements()[0].kind, ElementKind::floor);
  EXPECT_EQ(element_named(world, "wall x+").kind, ElementKind::wall);
  EXPECT_EQ(element_named(world, "ceiling").kind, ElementKind::wall);
  EXPECT_EQ(element_named(world, "shelf 0 post between columns 1 and 2, front face").kind,
            ElementKind::post);
  EXPECT_EQ(element_named(world, "shelf 0 beam under level 1, back face").kind, ElementKind::beam);
  EXPECT_EQ(element_named(world, "shelf 0 beam over level 4, front face").kind, ElementKind::beam);
  EXPECT_EQ(element_named(world, "shelf 0 rail under level 3, right of column 4").kind,
            ElementKind::rail);
  EXPECT_EQ(element_named(world, "shelf 0 box marker 7 (level 2, column 3)").shelf, 0);
  EXPECT_EQ(element_named(world,
                          "shelf 0 tag at post left of column 1, beam under level 1, back face")
                .kind,
            ElementKind::tag);
}

TEST(CollisionWorld, FlightThroughCellCentreTouchesNothing) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // Level 2, column 1 (narrow, empty): centre y = 0.65, z = 0.81; through the whole depth.
  EXPECT_FALSE(fly(world, {2.0, 0.65, 0.81}, {4.5, 0.65, 0.81}, 8.0));
  // The wide empty cell of level 2 (column 2: y = 0.24), slowly, and as one long sweep.
  EXPECT_FALSE(fly(world, {2.0, 0.24, 0.81}, {4.5, 0.24, 0.81}, 0.5));
  EXPECT_FALSE(world.sweep(pose({2.0, 0.24, 0.81}), 0, pose({4.5, 0.24, 0.81}), kNsPerSecond));
  // Yawing by 20 degrees while crossing the wide cell still clears its posts.
  EXPECT_FALSE(world.sweep(pose({2.0, 0.24, 0.81}, -0.17), 0, pose({4.5, 0.24, 0.81}, 0.17),
                           kNsPerSecond));
}

TEST(CollisionWorld, OneMillimetreOverlapWithPostIsCaughtAndNamed) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // Post between columns 1 and 2 sits at y = 0.48, its column-1 side at y = 0.49. The vehicle's
  // right side (half width 0.04625 + 0.01 margin) is at y - 0.05625.
  const double half_y = 0.5 * kTello.y() + kMargin;
  const double y_touch = 0.49 + half_y;
  EXPECT_FALSE(fly(world, {2.0, y_touch + 0.001, 0.81}, {4.5, y_touch + 0.001, 0.81}, 8.0))
      << "1 mm clear of the post";
  const auto c = fly(world, {2.0, y_touch - 0.001, 0.81}, {4.5, y_touch - 0.001, 0.81}, 8.0);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->element.name, "shelf 0 post between columns 1 and 2, front face");
  EXPECT_EQ(c->element.kind, ElementKind::post);
  EXPECT_EQ(c->element.shelf, 0);
  // First touch: the vehicle's front (x + 0.059) meets the post's front surface x = 2.99,
  // at x = 2.931, i.e. (2.931 - 2.0) / 8 s after the start.
  const double half_x = 0.5 * kTello.x() + kMargin;
  const double t_expected_s = (2.99 - half_x - 2.0) / 8.0;
  EXPECT_NEAR(ns_to_seconds(c->t_ns), t_expected_s, 1e-6);
  EXPECT_NEAR(c->point_W_m.x(), 2.99, 1e-6);
  EXPECT_GE(c->point_W_m.y(), 0.49 - 0.001 - 1e-9);
  EXPECT_LE(c->point_W_m.y(), 0.49 + 1e-9);
  EXPECT_NEAR(c->normal_W.x(), -1.0, 1e-6);  // from the post toward the vehicle
  EXPECT_NEAR(c->depth_m, 0.0, 1e-6);
}

TEST(CollisionWorld, PenetrationDepthAndNormalAtOnePose) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  const double half_y = 0.5 * kTello.y() + kMargin;
  // Inside the front plane, 1 mm into the post's column-1 side.
  const auto hits = world.overlaps(pose({3.0, 0.49 + half_y - 0.001, 0.81}), 123);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].element.name, "shelf 0 post between columns 1 and 2, front face");
  EXPECT_EQ(hits[0].t_ns, 123);
  EXPECT_NEAR(hits[0].depth_m, 0.001, 1e-9);
  EXPECT_NEAR(hits[0].normal_W.y(), 1.0, 1e-9);  // pushes the vehicle back into column 1
  EXPECT_NEAR(world.distance_to(pose({3.0, 0.49 + half_y - 0.001, 0.81}), hits[0].element.id),
              -0.001, 1e-9);
  // A sweep starting there reports it at the start time with its depth.
  const auto c = world.sweep(pose({3.0, 0.49 + half_y - 0.001, 0.81}), 1000,
                             pose({3.0, 0.65, 0.81}), 1000 + kStepNs);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->t_ns, 1000);
  EXPECT_NEAR(c->depth_m, 0.001, 1e-9);
}

TEST(CollisionWorld, FastPassThroughBeamIsCaught) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // Climbing at 8 m/s through the 2 cm beam between levels 2 and 3 (z = 0.98) inside the front
  // plane of column 1, in 2 ms steps (16 mm each).
  const auto c = fly(world, {3.0, 0.65, 0.81}, {3.0, 0.65, 1.15}, 8.0);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->element.kind, ElementKind::beam);
  EXPECT_EQ(c->element.name, "shelf 0 beam under level 3, front face");
  const double half_z = 0.5 * kTello.z() + kMargin;
  EXPECT_NEAR(ns_to_seconds(c->t_ns), (0.97 - half_z - 0.81) / 8.0, 1e-6);

  // One coarse step that starts below and ends above the beam, both ends clear of everything:
  // no discrete check can see it; the sweep does, at the right time.
  const Eigen::Isometry3d below = pose({3.0, 0.65, 0.97 - half_z - 0.004});
  const Eigen::Isometry3d above = pose({3.0, 0.65, 0.99 + half_z + 0.004});
  EXPECT_TRUE(world.overlaps(below, 0).empty());
  EXPECT_TRUE(world.overlaps(above, 10 * kStepNs).empty());
  const auto straddle = world.sweep(below, 0, above, 10 * kStepNs);
  ASSERT_TRUE(straddle);
  EXPECT_EQ(straddle->element.name, "shelf 0 beam under level 3, front face");
  // 4 mm of a (0.02 + 2 half_z + 0.008) m climb in 20 ms.
  const double climb_m = 0.02 + 2.0 * half_z + 0.008;
  EXPECT_NEAR(static_cast<double>(straddle->t_ns), 0.004 / climb_m * 20e6, 2.0);
}

TEST(CollisionWorld, RotationWithinOneStepIsSwept) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // In the front plane of column 1, level 2, 0.07 m from the column-1 side of the right post
  // (y = 0.49). Yaw 0: half width 0.05625 is clear; yaw 90 deg: half length 0.059 is clear; in
  // between, at 45 deg, the corners reach (0.059 + 0.05625) / sqrt(2) = 0.0815 > 0.07.
  const Eigen::Vector3d p(3.0, 0.49 + 0.07, 0.81);
  const Eigen::Isometry3d X0 = pose(p, 0.0), X1 = pose(p, std::numbers::pi / 2);
  EXPECT_TRUE(world.overlaps(X0, 0, FloorContacts::ignore).empty());
  EXPECT_TRUE(world.overlaps(X1, kStepNs, FloorContacts::ignore).empty());
  const auto c = world.sweep(X0, 0, X1, kStepNs);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->element.name, "shelf 0 post between columns 1 and 2, front face");
  EXPECT_GT(c->t_ns, 0);
  EXPECT_LT(c->t_ns, kStepNs / 2);
  // At the reported time the vehicle is (within the tolerance) touching, not overlapping.
  const double s = static_cast<double>(c->t_ns) / static_cast<double>(kStepNs);
  EXPECT_GT(world.distance_to(pose(p, s * std::numbers::pi / 2), c->element.id), -1e-6);
}

TEST(CollisionWorld, LandedIsFloorContactNotShelfHit) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // Resting on the floor 3 m in front of the shelf: the margin reaches 1 cm into the floor.
  const Eigen::Isometry3d landed = pose({0.0, 0.0, 0.5 * kTello.z()});
  const auto hits = world.overlaps(landed, 0);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].element.kind, ElementKind::floor);
  EXPECT_EQ(hits[0].element.name, "floor");
  EXPECT_NEAR(hits[0].depth_m, kMargin, 1e-12);
  EXPECT_NEAR(hits[0].normal_W.z(), 1.0, 1e-12);
  EXPECT_NEAR(hits[0].point_W_m.z(), 0.0, 1e-12);
  EXPECT_TRUE(world.overlaps(landed, 0, FloorContacts::ignore).empty());
  // Sitting still or taking off: a floor contact when asked, nothing when the floor is ignored.
  const Eigen::Isometry3d up = pose({0.0, 0.0, 0.3});
  const auto c = world.sweep(landed, 0, up, kStepNs);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->element.kind, ElementKind::floor);
  EXPECT_FALSE(is_shelf_part(c->element.kind));
  EXPECT_FALSE(world.sweep(landed, 0, landed, kStepNs, FloorContacts::ignore));
  EXPECT_FALSE(world.sweep(landed, 0, up, kStepNs, FloorContacts::ignore));
  // Taxiing on the floor into a post: the first contact that is not the floor is the post.
  const auto into_post =
      fly(world, {2.5, 0.48, 0.5 * kTello.z()}, {3.5, 0.48, 0.5 * kTello.z()}, 1.0, kStepNs,
          FloorContacts::ignore);
  ASSERT_TRUE(into_post);
  EXPECT_EQ(into_post->element.name, "shelf 0 post between columns 1 and 2, front face");
  // Taxiing under the lowest beam (0.30 m up) of an open cell touches nothing but the floor.
  EXPECT_FALSE(fly(world, {2.5, 0.65, 0.5 * kTello.z()}, {3.5, 0.65, 0.5 * kTello.z()}, 1.0,
                   kStepNs, FloorContacts::ignore));
}

TEST(CollisionWorld, ClearanceThroughCellCentreIsAnalytic) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  const double half_y = 0.5 * kTello.y() + kMargin;
  // Narrow cell (level 2, column 1) in its front plane: half clear width 0.16, so the side
  // posts are 0.16 - half_y away; beams are farther (0.16 - half_z).
  const Clearance narrow = world.clearance_to_shelves(pose({3.0, 0.65, 0.81}));
  EXPECT_NEAR(narrow.distance_m, 0.5 * (0.34 - 0.02) - half_y, 1e-6);
  EXPECT_EQ(narrow.element.kind, ElementKind::post);
  EXPECT_NE(narrow.element.name.find("front face"), std::string::npos);
  // 1 cm off centre toward the right post: that post, 1 cm nearer, exactly.
  const Clearance off = world.clearance_to_shelves(pose({3.0, 0.64, 0.81}));
  EXPECT_NEAR(off.distance_m, 0.5 * (0.34 - 0.02) - half_y - 0.01, 1e-6);
  EXPECT_EQ(off.element.name, "shelf 0 post between columns 1 and 2, front face");
  EXPECT_NEAR(off.point_on_element_W_m.y(), 0.49, 1e-6);
  // Wide cell (level 3, column 2, centre y = 0.24, z = 1.15) at mid-depth (x = 3.17): the
  // nearest parts are the four beams of the two faces above and below, an edge-to-edge distance
  // in the x-z plane (0.17 - 0.01 - half_x ahead or behind, 0.17 - 0.01 - half_z up or down).
  const double half_x = 0.5 * kTello.x() + kMargin;
  const double half_z = 0.5 * kTello.z() + kMargin;
  const Clearance wide = world.clearance_to_shelves(pose({3.17, 0.24, 1.15}));
  EXPECT_NEAR(wide.distance_m, std::hypot(0.16 - half_x, 0.16 - half_z), 1e-6);
  EXPECT_EQ(wide.element.kind, ElementKind::beam);
  // Yawed 45 degrees in the narrow cell's front plane: a corner points at the post's face.
  const Clearance yawed = world.clearance_to_shelves(pose({3.0, 0.65, 0.81}, std::numbers::pi / 4));
  EXPECT_NEAR(yawed.distance_m, 0.16 - (half_x + half_y) / std::sqrt(2.0), 1e-6);
  // Far away, facing an intersection: the tag card's face, at 3 m - 0.01 (half bar) - 0.001
  // (card), is the nearest.
  const Clearance far = world.clearance_to_shelves(pose({-1.5, 0.48, 0.64}));
  EXPECT_NEAR(far.distance_m, 4.5 - 0.011 - half_x, 1e-6);  // the tag cards sit in front
  EXPECT_EQ(far.element.kind, ElementKind::tag);
}

TEST(CollisionWorld, BoxesAndWallsAreHitAndNamed) {
  const CollisionWorld world(test_warehouse(), kTello, kMargin);
  // Level 2, column 3 holds the box with marker 7: centre y = -0.17, z = 0.81.
  const auto box = fly(world, {2.0, -0.17, 0.81}, {4.5, -0.17, 0.81}, 2.0);
  ASSERT_TRUE(box);
  EXPECT_EQ(box->element.name, "shelf 0 box marker 7 (level 2, column 3)");
  EXPECT_EQ(box->element.kind, ElementKind::box);
  // The box's front face is at x = 3.0 + (0.34 - 0.22) / 2 = 3.06.
  EXPECT_NEAR(box->point_W_m.x(), 3.06, 1e-6);
  // Backing into the wall x- at -2 m.
  const auto wall = fly(world, {0.0, 1.0, 1.0}, {-3.0, 1.0, 1.0}, 4.0);
  ASSERT_TRUE(wall);
  EXPECT_EQ(wall->element.name, "wall x-");
  EXPECT_NEAR(wall->point_W_m.x(), -2.0, 1e-12);
  // Every contact of a sweep, in time order: the box, then the wall x+ behind the shelf.
  const auto all = world.sweep_all(pose({2.0, -0.17, 0.81}), 0, pose({7.0, -0.17, 0.81}), kNsPerSecond);
  ASSERT_GE(all.size(), 2u);
  for (size_t i = 1; i < all.size(); ++i) EXPECT_LE(all[i - 1].t_ns, all[i].t_ns);
  EXPECT_EQ(all.front().element.name, "shelf 0 box marker 7 (level 2, column 3)");
  EXPECT_EQ(all.back().element.name, "wall x+");
}

// Solid decks (warehouse.hpp): one board on every cell floor, after every other element of the
// shelf (a shelf without decks keeps its ids); a vehicle sinking into an empty cell touches the
// deck's top where the open shelf has nothing; boxes stand on the deck.
TEST(CollisionWorld, SolidDecksAreTouchedAndCarryTheBoxes) {
  Warehouse w = test_warehouse();
  w.shelves[0].deck_thickness_m = 0.018;
  const CollisionWorld decked(w, kTello, kMargin);
  const CollisionWorld open(test_warehouse(), kTello, kMargin);
  ASSERT_EQ(decked.elements().size(), open.elements().size() + 4u);  // under levels 1 to 4
  for (size_t i = 0; i < open.elements().size(); ++i) EXPECT_EQ(decked.elements()[i], open.elements()[i]);
  const Element& deck = element_named(decked, "shelf 0 deck under level 2");
  EXPECT_EQ(deck.kind, ElementKind::deck);
  EXPECT_TRUE(is_shelf_part(deck.kind));
  EXPECT_STREQ(to_string(ElementKind::deck), "deck");
  // Level 2, column 2 (wide, empty): centre y = 0.24; its floor: beam 0.64 + 0.01 + 0.018 = 0.668.
  const auto c = fly(decked, {3.17, 0.24, 0.81}, {3.17, 0.24, 0.5}, 0.5);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->element.name, "shelf 0 deck under level 2");
  EXPECT_NEAR(c->point_W_m.z(), 0.668, 1e-9);
  // Without the deck the open cell floor (rails at its sides only, beams at its faces) lets the
  // vehicle sink through into the cell below.
  EXPECT_FALSE(fly(open, {3.17, 0.24, 0.81}, {3.17, 0.24, 0.5}, 0.5));
  // Clearance at the cell centre: to the deck 0.81 - 0.668 - 0.0205 - 0.01 below.
  EXPECT_NEAR(decked.clearance_to_shelves(pose({3.17, 0.24, 0.81})).distance_m, 0.81 - 0.668 - 0.0305, 1e-9);
  // The box with marker 7 (level 2, column 3) stands on the deck: its top at 0.668 + 0.22.
  const Element& box = element_named(decked, "shelf 0 box marker 7 (level 2, column 3)");
  const double above_m = decked.distance_to(pose({3.17, -0.17, 0.668 + 0.22 + 0.0305 + 0.05}), box.id);
  EXPECT_NEAR(above_m, 0.05, 1e-9);
}

TEST(CollisionWorld, RotatedShelfIsPlacedByItsPose) {
  Warehouse w = test_warehouse();
  // The shelf turned to face +y from y = 2: its front face is the plane y = 2, and its column 1
  // (left as seen on approach, i.e. toward -x) is centred at x = -0.65.
  w.shelves[0].origin_W_m = {0.0, 2.0, 0.0};
  w.shelves[0].yaw_rad = std::numbers::pi / 2;
  const CollisionWorld world(w, kTello, kMargin);
  const double half_y = 0.5 * kTello.y() + kMargin;
  const Eigen::Isometry3d X = pose({-0.65, 2.0, 0.81}, std::numbers::pi / 2);
  const Clearance c = world.clearance_to_shelves(X);
  EXPECT_NEAR(c.distance_m, 0.16 - half_y, 1e-6);
  EXPECT_EQ(c.element.kind, ElementKind::post);
  EXPECT_FALSE(world.sweep(pose({-0.65, 1.0, 0.81}, std::numbers::pi / 2), 0,
                           pose({-0.65, 3.0, 0.81}, std::numbers::pi / 2), kNsPerSecond));
}

TEST(CollisionWorld, NoShelvesGivesInfiniteClearance) {
  Warehouse w = test_warehouse();
  w.shelves.clear();
  const CollisionWorld world(w, kTello, 0.0);
  const Clearance c = world.clearance_to_shelves(pose({0.0, 0.0, 1.0}));
  EXPECT_TRUE(std::isinf(c.distance_m));
  EXPECT_EQ(c.element.id, -1);
}

// The downward ray from above a cell: the paper's shelf has open bars, so a ray down the middle
// of a cell passes through the empty cells below and reads the first box top; over a beam or a
// rail it reads that bar's top; clear of the shelf, the floor.
TEST(CollisionWorld, RayDownReadsTheBoxTopTheBeamTheRailOrTheFloor) {
  const Warehouse w = test_warehouse();
  const CollisionWorld world(w, kTello, kMargin);
  const ShelfSpec& s = w.shelves.front();
  const double bar_top_level3 = beam_z_S_m(s, 2) + 0.5 * s.beam_thickness_m;  // 0.99
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  // Over cell (level 3, column 1): levels 3 and 2 are empty, the box of level 1 is below.
  const double box1_top = beam_z_S_m(s, 0) + 0.5 * s.beam_thickness_m + w.box_size_m.z();  // 0.53
  const auto box = world.ray_cast({3.17, 0.65, 1.2}, down, 8.0);
  ASSERT_TRUE(box);
  EXPECT_EQ(box->element.kind, ElementKind::box);
  EXPECT_EQ(box->element.name, "shelf 0 box marker 3 (level 1, column 1)");
  EXPECT_NEAR(box->distance_m, 1.2 - box1_top, 1e-12);
  EXPECT_NEAR(box->point_W_m.z(), box1_top, 1e-12);
  // Over the front beam under level 3.
  const auto beam = world.ray_cast({3.0, 0.2, 1.2}, down, 8.0);
  ASSERT_TRUE(beam);
  EXPECT_EQ(beam->element.kind, ElementKind::beam);
  EXPECT_NEAR(beam->distance_m, 1.2 - bar_top_level3, 1e-12);
  // Over the rail under level 3 at the post between columns 1 and 2 (y_S = 0.48).
  const auto rail = world.ray_cast({3.17, 0.48, 1.2}, down, 8.0);
  ASSERT_TRUE(rail);
  EXPECT_EQ(rail->element.kind, ElementKind::rail);
  EXPECT_NEAR(rail->distance_m, 1.2 - bar_top_level3, 1e-12);
  // In front of the shelf: the floor; a range shorter than the floor's distance: nothing.
  const auto floor = world.ray_cast({1.0, 0.0, 1.0}, down, 8.0);
  ASSERT_TRUE(floor);
  EXPECT_EQ(floor->element.kind, ElementKind::floor);
  EXPECT_NEAR(floor->distance_m, 1.0, 1e-12);
  EXPECT_FALSE(world.ray_cast({1.0, 0.0, 1.0}, down, 0.9));
  // Tilted 30 deg about y_W, in front of the shelf and leaning away from it: the slant distance
  // to the floor.
  const Eigen::Vector3d slant(-std::sin(std::numbers::pi / 6), 0.0, -std::cos(std::numbers::pi / 6));
  const auto tilted = world.ray_cast({2.5, 0.65, 0.5}, slant, 8.0);
  ASSERT_TRUE(tilted);
  EXPECT_EQ(tilted->element.kind, ElementKind::floor);
  EXPECT_NEAR(tilted->distance_m, 0.5 / std::cos(std::numbers::pi / 6), 1e-12);
  // Upward from inside cell (3, 1): the middle of every cell above is open, so the ray reaches
  // the ceiling of the arena.
  const auto up = world.ray_cast({3.17, 0.65, 1.2}, -down, 100.0);
  ASSERT_TRUE(up);
  EXPECT_EQ(up->element.name, "ceiling");
  EXPECT_NEAR(up->distance_m, w.arena_max_W_m.z() - 1.2, 1e-12);
  // An origin inside a box meets it at once.
  const auto inside = world.ray_cast({3.17, 0.65, box1_top - 0.05}, down, 8.0);
  ASSERT_TRUE(inside);
  EXPECT_EQ(inside->element.kind, ElementKind::box);
  EXPECT_EQ(inside->distance_m, 0.0);
}

}  // namespace
}  // namespace shelfcross::plant
