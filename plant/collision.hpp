#pragma once
// The world the vehicle can hit: every bar, tag and box of every shelf, the floor, the walls and
// the ceiling of the arena, with continuous (swept) collision checking of the vehicle between
// two plant steps and exact box-to-box clearance queries.
//
// Geometry built from a Warehouse (conventions of include/shelfcross/warehouse.hpp), all in
// the shelf frame S, then placed by X_WS. With T_p = post_thickness_m, T_b = beam_thickness_m,
// D = depth_m, faces at x_S = 0 (front) and x_S = D (back), z_top = beam_z_S_m(nrows):
//   post  (boundary i, face):  square T_p x T_p, centred on (x_face, post_y_S_m(i)), from the
//                              floor z_S = 0 up to the top of the top beam, z_top + T_b / 2;
//   beam  (boundary j, face):  square T_b x T_b along y_S, centred on (x_face, z = beam_z_S_m(j)),
//                              from the outer side of the leftmost post to that of the rightmost;
//   rail  (boundary i, j):     along x_S from the front centre line to the back one (x_S 0..D),
//                              T_p wide (y_S) and T_b high (z_S), so that a cell's clear opening
//                              is (column pitch - T_p) x (row pitch - T_b) all the way through;
//   tag   (i, j, face):        a tag_size_m square card kTagThickness_m thick on the outer surface
//                              of the intersection (x_S = -max(T_p, T_b) / 2 outward); a tag is
//                              stuck to the shelf, so touching it is touching the shelf;
//   deck  (boundary j < nrows): only where deck_thickness_m > 0: a board from the top of the
//                              beams (z = beam_z(j) + T_b / 2) up by deck_thickness_m, x_S 0..D,
//                              across the shelf between the outer posts' centre lines;
//   box   (placement):         box_size_m, centred on its cell's (y, x_S = D / 2) and standing on
//                              its cell's floor (cell_floor_z_S_m: the rails, or the deck).
// Element ids follow this order per shelf (posts, beams, rails, tags, boxes, then decks), so a
// shelf without decks has the ids it had before decks existed.
// The floor is the half-space z < 0; the walls and the ceiling are the half-spaces outside the
// arena box (arena_min_W_m, arena_max_W_m), exact for any distance (no thin slabs to tunnel).
//
// The vehicle is an oriented box: VehicleParams::size_m (propellers included) plus `margin_m`
// on every side, centred on the body origin B with the body axes.
//
// Distances are exact box-to-box distances (Bullet's GJK, btGjkEpaSolver2, with zero collision
// margins, for shelf elements; closed form for the half-spaces), signed: negative when the two
// overlap, its magnitude then being the penetration depth (EPA: the shortest translation that
// separates them). Two shapes closer than kContactTolerance_m count as touching.
//
// Swept test (sweep): the vehicle moves from X_WB_from to X_WB_to with its position linear and
// its attitude the slerp between the two, both in the fraction s in [0, 1] of the step. For each
// element whose bounds meet the swept bounds (Bullet's dynamic AABB tree broadphase), conservative
// advancement finds the first s at which the distance falls below kContactTolerance_m: with n the
// unit normal from the element toward the vehicle at the closest points, d the distance, dp the
// step's translation, theta its rotation angle and r the vehicle's half diagonal, no point of the
// vehicle approaches the separating plane faster than (-n . dp + theta * r) per unit s, so
// advancing s by d / (-n . dp + theta * r) cannot pass through anything (no tunnelling, whatever
// the speed, the step or the bar). A start pose already touching or overlapping is a contact at
// the step's start time with its penetration depth.
//
// Ray cast (ray_cast): the first surface a ray meets, for the sensors that look at the world (the
// downward range sensor and the vision positioning system). Candidates are the shelf parts whose
// bounds meet the ray segment's bounds (the same broadphase); each box is met in closed form
// (the slab method in the box's own frame: the ray's parameter interval inside each pair of
// faces, intersected); the half-spaces by n . (o + t u) = c. An origin inside an element meets it
// at distance 0.
//
// Thread safety: queries are const and use only thread-local scratch space, so one world may be
// queried by several threads at once (the runs of a campaign can share it).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "shelfcross/time.hpp"
#include "shelfcross/warehouse.hpp"

namespace shelfcross::plant {

enum class ElementKind { floor, wall, post, beam, rail, tag, box, deck };
/// Every kind, in declaration order (readers of a stored kind name look it up here).
inline constexpr ElementKind kElementKinds[] = {ElementKind::floor, ElementKind::wall, ElementKind::post,
                                                ElementKind::beam,  ElementKind::rail, ElementKind::tag,
                                                ElementKind::box,   ElementKind::deck};

/// "floor", "wall", "post", ... for logs and reports.
const char* to_string(ElementKind kind);

/// One thing the vehicle can touch. `id` indexes CollisionWorld::elements().
struct Element {
  int id = -1;
  ElementKind kind = ElementKind::floor;
  int shelf = -1;  ///< index into Warehouse::shelves; -1 for floor, walls and ceiling
  std::string name;  ///< e.g. "shelf 0 post between columns 1 and 2, front face", "floor", "wall x+"
  bool operator==(const Element&) const = default;
};

/// True for the parts of a shelf (bars, tags, boxes, decks); false for floor, walls and ceiling.
inline bool is_shelf_part(ElementKind kind) {
  return kind != ElementKind::floor && kind != ElementKind::wall;
}

struct Contact {
  TimeNs t_ns = 0;                       ///< first touch, interpolated within the step
  Element element;
  Eigen::Vector3d point_W_m = Eigen::Vector3d::Zero();  ///< on the element's surface
  Eigen::Vector3d normal_W = Eigen::Vector3d::Zero();   ///< unit, from the element toward the vehicle
  double depth_m = 0.0;                  ///< penetration depth, >= 0 (0: touching)
};

struct Clearance {
  double distance_m = 0.0;  ///< signed: < 0 when overlapping; +infinity when there is no shelf
  Element element;          ///< the nearest shelf part (id -1 when there is no shelf)
  Eigen::Vector3d point_on_element_W_m = Eigen::Vector3d::Zero();
};

/// Whether a query reports the floor. A landed vehicle always touches the floor, so the harness
/// asks for the first contact that is not the floor while on the ground.
enum class FloorContacts { report, ignore };

/// The first surface met by a ray (CollisionWorld::ray_cast).
struct RayHit {
  double distance_m = 0.0;  ///< from the ray's origin along its direction, >= 0
  Element element;          ///< what was met: its kind says floor, box top, beam, rail, ...
  Eigen::Vector3d point_W_m = Eigen::Vector3d::Zero();
};

class CollisionWorld {
 public:
  /// Distances below this count as touching (a contact). Far below any geometric tolerance.
  static constexpr double kContactTolerance_m = 1e-6;
  /// Thickness of a colour tag card.
  static constexpr double kTagThickness_m = 0.001;

  /// Builds the world. Preconditions (asserted; scenario loading validates user input): at
  /// least one column and row per shelf, positive sizes, boxes in existing cells,
  /// vehicle_size_m > 0, margin_m >= 0.
  CollisionWorld(const Warehouse& warehouse, const Eigen::Vector3d& vehicle_size_m, double margin_m);
  ~CollisionWorld();
  CollisionWorld(CollisionWorld&&) noexcept;
  CollisionWorld& operator=(CollisionWorld&&) noexcept;
  CollisionWorld(const CollisionWorld&) = delete;
  CollisionWorld& operator=(const CollisionWorld&) = delete;

  /// The first contact along the motion from X_WB_from (at t_from_ns) to X_WB_to (at t_to_ns),
  /// t_to_ns >= t_from_ns (a precondition, asserted); nullopt when the vehicle touches nothing during the step. Its time is
  /// t_from_ns + floor(s * (t_to_ns - t_from_ns)) for the first-touch fraction s. Ties between
  /// elements are broken by the lower element id.
  std::optional<Contact> sweep(const Eigen::Isometry3d& X_WB_from, TimeNs t_from_ns,
                               const Eigen::Isometry3d& X_WB_to, TimeNs t_to_ns,
                               FloorContacts floor = FloorContacts::report) const;

  /// Every element touched during the motion, each once at its own first touch, sorted by time
  /// (then element id).
  std::vector<Contact> sweep_all(const Eigen::Isometry3d& X_WB_from, TimeNs t_from_ns,
                                 const Eigen::Isometry3d& X_WB_to, TimeNs t_to_ns,
                                 FloorContacts floor = FloorContacts::report) const;

  /// Every element the vehicle touches or overlaps at one pose, by element id, with depths.
  std::vector<Contact> overlaps(const Eigen::Isometry3d& X_WB, TimeNs t_ns,
                                FloorContacts floor = FloorContacts::report) const;

  /// The nearest shelf part (post, beam, rail, tag, box or deck; not floor, walls or ceiling) and the
  /// exact signed box-to-box distance to it.
  Clearance clearance_to_shelves(const Eigen::Isometry3d& X_WB) const;

  /// The first element (shelf part, floor, wall or ceiling) met by the ray from origin_W_m along
  /// direction_W (any length > 0; normalised here) within max_range_m, or nullopt. Ties between
  /// elements at the same distance go to the lower element id. Preconditions (asserted): a
  /// direction of length > 0, max_range_m >= 0.
  std::optional<RayHit> ray_cast(const Eigen::Vector3d& origin_W_m, const Eigen::Vector3d& direction_W,
                                 double max_range_m) const;

  /// Signed distance from the vehicle at X_WB to one element (see the header comment);
  /// element_id must index elements() (asserted).
  double distance_to(const Eigen::Isometry3d& X_WB, int element_id) const;

  const std::vector<Element>& elements() const;
  /// Half extents of the vehicle box used for checks: size / 2 + margin.
  const Eigen::Vector3d& vehicle_half_extents_m() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::plant
