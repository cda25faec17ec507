#include "plant/collision.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <btBulletCollisionCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

namespace shelfcross::plant {
namespace {

btVector3 to_bt(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d to_eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

btTransform to_bt(const Eigen::Isometry3d& X) {
  const Eigen::Matrix3d& R = X.linear();
  btMatrix3x3 basis(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2));
  return btTransform(basis, to_bt(X.translation()));
}

/// Signed distance between the vehicle and one element, with the closest points.
struct SignedDistance {
  double d = std::numeric_limits<double>::infinity();
  Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();  ///< element -> vehicle
  Eigen::Vector3d point_on_element_W = Eigen::Vector3d::Zero();
};

/// A solid half-space {x : n . x <= c}; n is the unit normal pointing out of the solid.
struct HalfSpace {
  Eigen::Vector3d n;
  double c;
};

/// The vehicle's motion over one step: position linear, attitude slerped, in s in [0, 1].
struct Motion {
  Eigen::Vector3d p0, dp;
  Eigen::Quaterniond q0, q1;
  double theta_rad;  ///< rotation angle between the two attitudes
  Eigen::Isometry3d at(double s) const {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = (theta_rad > 0.0 ? q0.slerp(s, q1) : q0).toRotationMatrix();
    X.translation() = p0 + s * dp;
    return X;
  }
};

Motion make_motion(const Eigen::Isometry3d& X_from, const Eigen::Isometry3d& X_to) {
  Motion m;
  m.p0 = X_from.translation();
  m.dp = X_to.translation() - X_from.translation();
  m.q0 = Eigen::Quaterniond(X_from.linear()).normalized();
  m.q1 = Eigen::Quaterniond(X_to.linear()).normalized();
  // Eigen's slerp takes the shorter arc; the angle of that arc is 2 acos(|q0 . q1|).
  const double c = std::min(1.0, std::abs(m.q0.dot(m.q1)));
  m.theta_rad = 2.0 * std::acos(c);
  return m;
}

// Collects the ids of the objects whose AABB meets the query box.
struct AabbCollector : btBroadphaseAabbCallback {
  std::vector<int>* ids = nullptr;
  bool process(const btBroadphaseProxy* proxy) override {
    ids->push_back(static_cast<const btCollisionObject*>(proxy->m_clientObject)->getUserIndex());
    return true;
  }
};

std::string face_name(int face) { return face == 0 ? "front face" : "back face"; }

std::string boundary_column_name(int i, int ncols) {
  if (i == 0) return "left of column 1";
  if (i == ncols) return "right of column " + std::to_string(ncols);
  return "between columns " + std::to_string(i) + " and " + std::to_string(i + 1);
}

std::string boundary_level_name(int j, int nrows) {
  if (j == nrows) return "over level " + std::to_string(nrows);
  return "under level " + std::to_string(j + 1);
}

}  // namespace

const char* to_string(ElementKind kind) {
  switch (kind) {
    case ElementKind::floor: return "floor";
    case ElementKind::wall: return "wall";
    case ElementKind::post: return "post";
    case ElementKind::beam: return "beam";
    case ElementKind::rail: return "rail";
    case ElementKind::tag: return "tag";
    case ElementKind::box: return "box";
    case ElementKind::deck: return "deck";
  }
  return "?";
}

struct CollisionWorld::Impl {
  std::vector<Element> elements;
  // Per element: a half-space (floor, walls, ceiling) or a Bullet box (shelf parts).
  std::vector<std::optional<HalfSpace>> half_spaces;
  std::vector<int> half_space_ids;
  Eigen::Vector3d vehicle_half_m;
  double vehicle_radius_m;  ///< half diagonal of the vehicle box: bound on |R r| for its points

  // Declaration order is destruction order reversed: the world goes first, while the objects,
  // shapes and broadphase it refers to still exist.
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  std::unique_ptr<btBoxShape> vehicle_shape;
  std::vector<std::unique_ptr<btBoxShape>> shapes;                // by element id (null: half-space)
  std::vector<std::unique_ptr<btCollisionObject>> objects;        // by element id (null: half-space)
  // By element id, for the ray cast: each box's pose X_WE and half extents (unused for half-spaces).
  std::vector<Eigen::Isometry3d> box_poses;
  std::vector<Eigen::Vector3d> box_halves;
  std::unique_ptr<btCollisionWorld> world;

  void add_half_space(ElementKind kind, const std::string& name, const Eigen::Vector3d& n, double c) {
    const int id = static_cast<int>(elements.size());
    elements.push_back({id, kind, -1, name});
    half_spaces.push_back(HalfSpace{n, c});
    half_space_ids.push_back(id);
    shapes.emplace_back();
    objects.emplace_back();
    box_poses.emplace_back(Eigen::Isometry3d::Identity());
    box_halves.emplace_back(Eigen::Vector3d::Zero());
  }

  void add_box(ElementKind kind, int shelf, const std::string& name, const Eigen::Isometry3d& X_WS,
               const Eigen::Vector3d& centre_S_m, const Eigen::Vector3d& half_S_m) {
    assert((half_S_m.array() > 0.0).all());
    const int id = static_cast<int>(elements.size());
    elements.push_back({id, kind, shelf, name});
    half_spaces.emplace_back();
    auto shape = std::make_unique<btBoxShape>(to_bt(half_S_m));
    shape->setMargin(0.0);  // exact box: Bullet's default margin would round its corners
    Eigen::Isometry3d X_WE = X_WS;
    X_WE.translation() = X_WS * centre_S_m;
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(shape.get());
    object->setWorldTransform(to_bt(X_WE));
    object->setUserIndex(id);
    world->addCollisionObject(object.get());
    shapes.push_back(std::move(shape));
    objects.push_back(std::move(object));
    box_poses.push_back(X_WE);
    box_halves.push_back(half_S_m);
  }

  /// Where the ray o + t u (t >= 0, u unit) first meets element `id`, or nullopt: the slab method
  /// for a box, the plane for a half-space (header comment).
  std::optional<double> ray_parameter(int id, const Eigen::Vector3d& o, const Eigen::Vector3d& u) const {
    if (const auto& h = half_spaces[static_cast<size_t>(id)]) {
      const double height = h->n.dot(o) - h->c;  // > 0 outside the solid
      if (height <= 0.0) return 0.0;
      const double closing = -h->n.dot(u);
      if (!(closing > 0.0)) return std::nullopt;
      return height / closing;
    }
    const Eigen::Isometry3d& X = box_poses[static_cast<size_t>(id)];
    const Eigen::Vector3d& half = box_halves[static_cast<size_t>(id)];
    const Eigen::Vector3d o_E = X.linear().transpose() * (o - X.translation());
    const Eigen::Vector3d u_E = X.linear().transpose() * u;
    double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      if (u_E[k] == 0.0) {
        if (std::abs(o_E[k]) > half[k]) return std::nullopt;  // parallel to the slab, outside it
        continue;
      }
      const double t1 = (-half[k] - o_E[k]) / u_E[k], t2 = (half[k] - o_E[k]) / u_E[k];
      t_in = std::max(t_in, std::min(t1, t2));
      t_out = std::min(t_out, std::max(t1, t2));
    }
    if (t_in > t_out) return std::nullopt;
    return t_in;
  }

  void add_shelf(int index, const ShelfSpec& s, const Warehouse& w) {
    const int ncols = static_cast<int>(s.column_pitch_m.size());
    const int nrows = static_cast<int>(s.row_pitch_m.size());
    assert(ncols >= 1 && nrows >= 1);
    const double tp = s.post_thickness_m, tb = s.beam_thickness_m, depth = s.depth_m;
    const double z_top = beam_z_S_m(s, nrows) + 0.5 * tb;
    const double y_left = post_y_S_m(s, 0), y_right = post_y_S_m(s, ncols);
    const Eigen::Isometry3d X_WS = shelf_pose_W(s);
    const std::string shelf = "shelf " + std::to_string(index) + " ";
    const double x_face[2] = {0.0, depth};
    for (int f = 0; f < 2; ++f) {
      for (int i = 0; i <= ncols; ++i) {
        add_box(ElementKind::post, index,
                shelf + "post " + boundary_column_name(i, ncols) + ", " + face_name(f), X_WS,
                {x_face[f], post_y_S_m(s, i), 0.5 * z_top}, {0.5 * tp, 0.5 * tp, 0.5 * z_top});
      }
      for (int j = 0; j <= nrows; ++j) {
        add_box(ElementKind::beam, index,
                shelf + "beam " + boundary_level_name(j, nrows) + ", " + face_name(f), X_WS,
                {x_face[f], 0.5 * (y_left + y_right), beam_z_S_m(s, j)},
                {0.5 * tb, 0.5 * (y_left - y_right + tp), 0.5 * tb});
      }
    }
    for (int j = 0; j <= nrows; ++j) {
      for (int i = 0; i <= ncols; ++i) {
        add_box(ElementKind::rail, index,
                shelf + "rail " + boundary_level_name(j, nrows) + ", " +
                    boundary_column_name(i, ncols),
                X_WS, {0.5 * depth, post_y_S_m(s, i), beam_z_S_m(s, j)},
                {0.5 * depth, 0.5 * tp, 0.5 * tb});
      }
    }
    // Tags: on the outer surface of every intersection, both faces.
    const double bar_half = 0.5 * std::max(tp, tb);
    const double tag_x[2] = {-bar_half - 0.5 * kTagThickness_m, depth + bar_half + 0.5 * kTagThickness_m};
    for (int f = 0; f < 2; ++f) {
      for (int j = 0; j <= nrows; ++j) {
        for (int i = 0; i <= ncols; ++i) {
          add_box(ElementKind::tag, index,
                  shelf + "tag at post " + boundary_column_name(i, ncols) + ", beam " +
                      boundary_level_name(j, nrows) + ", " + face_name(f),
                  X_WS, {tag_x[f], post_y_S_m(s, i), beam_z_S_m(s, j)},
                  {0.5 * kTagThickness_m, 0.5 * w.tag_size_m, 0.5 * w.tag_size_m});
        }
      }
    }
    for (const BoxPlacement& b : s.boxes) {
      assert(b.level >= 1 && b.level <= nrows && b.column >= 1 && b.column <= ncols);
      const Eigen::Vector3d cell = cell_centre_S_m(s, b.level, b.column);
      add_box(ElementKind::box, index,
              shelf + "box marker " + std::to_string(b.marker_id) + " (level " +
                  std::to_string(b.level) + ", column " + std::to_string(b.column) + ")",
              X_WS, {0.5 * depth, cell.y(), cell_floor_z_S_m(s, b.level) + 0.5 * w.box_size_m.z()},
              0.5 * w.box_size_m);
    }
    if (s.deck_thickness_m > 0.0) {
      const double t = s.deck_thickness_m;
      for (int j = 0; j < nrows; ++j) {
        add_box(ElementKind::deck, index, shelf + "deck " + boundary_level_name(j, nrows), X_WS,
                {0.5 * depth, 0.5 * (y_left + y_right), beam_z_S_m(s, j) + 0.5 * tb + 0.5 * t},
                {0.5 * depth, 0.5 * (y_left - y_right), 0.5 * t});
      }
    }
  }

  /// World pose of the vehicle box for Bullet.
  SignedDistance distance(const Eigen::Isometry3d& X_WB, int id) const {
    SignedDistance out;
    if (const auto& h = half_spaces[static_cast<size_t>(id)]) {
      // Box {p + R diag(h) u, |u_k| <= 1} against {n . x <= c}: the deepest corner is
      // p - sum_k h_k sign(n . R_k) R_k, at signed height n . p - c - sum_k h_k |n . R_k|.
      const Eigen::Matrix3d& R = X_WB.linear();
      Eigen::Vector3d corner = X_WB.translation();
      for (int k = 0; k < 3; ++k) {
        const double nk = h->n.dot(R.col(k));
        corner -= vehicle_half_m[k] * (nk >= 0.0 ? 1.0 : -1.0) * R.col(k);
      }
      out.d = h->n.dot(corner) - h->c;
      out.normal_W = h->n;
      out.point_on_element_W = corner - out.d * h->n;
      return out;
    }
    const btCollisionObject& object = *objects[static_cast<size_t>(id)];
    const btTransform X_vehicle = to_bt(X_WB);
    const btTransform& X_element = object.getWorldTransform();
    const btConvexShape* shape = shapes[static_cast<size_t>(id)].get();
    btGjkEpaSolver2::sResults r;
    const btVector3 guess = X_element.getOrigin() - X_vehicle.getOrigin();
    if (btGjkEpaSolver2::Distance(vehicle_shape.get(), X_vehicle, shape, X_element, guess, r)) {
      // Separated: witnesses[0] on the vehicle, [1] on the element; the normal is their
      // difference, taken here from the witnesses so that it points element -> vehicle.
      out.d = r.distance;
      out.point_on_element_W = to_eigen(r.witnesses[1]);
      out.normal_W = to_eigen(r.witnesses[0] - r.witnesses[1]);
    } else if (btGjkEpaSolver2::Penetration(vehicle_shape.get(), X_vehicle, shape, X_element,
                                            guess, r)) {
      // Overlapping: EPA gives distance = -depth, witnesses[0] the vehicle's deepest point,
      // witnesses[1] the element's surface point, and a normal pointing element -> vehicle
      // (moving the vehicle by depth along it separates the two; checked by the tests).
      out.d = r.distance;
      out.point_on_element_W = to_eigen(r.witnesses[1]);
      out.normal_W = to_eigen(r.normal);
    } else {
      // Both phases failed: the shapes are exactly touching (degenerate simplex). Distance 0.
      out.d = 0.0;
      out.point_on_element_W = to_eigen(r.witnesses[1]);
      out.normal_W = X_WB.translation() - to_eigen(X_element.getOrigin());
    }
    const double length = out.normal_W.norm();
    out.normal_W = length > 0.0 ? Eigen::Vector3d(out.normal_W / length) : Eigen::Vector3d::UnitZ();
    return out;
  }

  /// Shelf-part element ids whose AABB meets [lo, hi], sorted; then every half-space id if asked.
  void candidates(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, FloorContacts floor,
                  bool with_half_spaces, std::vector<int>& ids) const {
    ids.clear();
    AabbCollector collect;
    collect.ids = &ids;
    const_cast<btDbvtBroadphase&>(broadphase).aabbTest(to_bt(lo), to_bt(hi), collect);
    std::sort(ids.begin(), ids.end());
    if (!with_half_spaces) return;
    for (int id : half_space_ids) {
      if (floor == FloorContacts::ignore && elements[static_cast<size_t>(id)].kind == ElementKind::floor) {
        continue;
      }
      ids.push_back(id);
    }
  }

  Contact make_contact(int id, const SignedDistance& sd, TimeNs t_ns) const {
    return {t_ns, elements[static_cast<size_t>(id)], sd.point_on_element_W, sd.normal_W,
            std::max(0.0, -sd.d)};
  }

  /// Conservative advancement against one element (header comment): the first fraction s <=
  /// s_max at which the distance is below the tolerance, or nullopt.
  std::optional<std::pair<double, SignedDistance>> first_touch(const Motion& m, int id,
                                                               double s_max) const {
    constexpr int kMaxIterations = 64;
    double s = 0.0;
    SignedDistance sd;
    for (int it = 0; it < kMaxIterations; ++it) {
      sd = distance(m.at(s), id);
      if (sd.d < kContactTolerance_m) return std::make_pair(s, sd);
      const double approach = -sd.normal_W.dot(m.dp) + m.theta_rad * vehicle_radius_m;
      if (!(approach > 0.0)) return std::nullopt;  // moving away from the separating plane
      s += sd.d / approach;
      if (s > s_max) return std::nullopt;
    }
    // Still creeping toward the element after many steps: it is within a hair of it. Count it
    // as a touch (the conservative answer) at the last safe fraction.
    return std::make_pair(s, sd);
  }

  std::vector<Contact> sweep(const Eigen::Isometry3d& X_from, TimeNs t_from_ns,
                             const Eigen::Isometry3d& X_to, TimeNs t_to_ns, FloorContacts floor,
                             bool first_only) const {
    assert(t_to_ns >= t_from_ns);
    const Motion m = make_motion(X_from, X_to);
    // Swept bounds: the segment of centres, widened by the vehicle's half diagonal (which bounds
    // every attitude on the way).
    const Eigen::Vector3d a = X_from.translation(), b = X_to.translation();
    const Eigen::Vector3d pad = Eigen::Vector3d::Constant(vehicle_radius_m + kContactTolerance_m);
    thread_local std::vector<int> ids;
    candidates(a.cwiseMin(b) - pad, a.cwiseMax(b) + pad, floor, true, ids);
    std::vector<Contact> out;
    double s_best = 1.0;
    const double dt = static_cast<double>(t_to_ns - t_from_ns);
    for (int id : ids) {
      const auto hit = first_touch(m, id, first_only ? s_best : 1.0);
      if (!hit) continue;
      const auto [s, sd] = *hit;
      const TimeNs t = std::clamp<TimeNs>(t_from_ns + static_cast<TimeNs>(std::floor(s * dt)),
                                          t_from_ns, t_to_ns);
      if (first_only) {
        // Ids are visited in increasing order: a strictly earlier touch replaces the best.
        if (out.empty() || s < s_best) {
          out.assign(1, make_contact(id, sd, t));
          s_best = s;
        }
      } else {
        out.push_back(make_contact(id, sd, t));
      }
    }
    std::stable_sort(out.begin(), out.end(), [](const Contact& x, const Contact& y) {
      return x.t_ns != y.t_ns ? x.t_ns < y.t_ns : x.element.id < y.element.id;
    });
    return out;
  }

  Eigen::Vector3d aabb_half(const Eigen::Isometry3d& X_WB) const {
    return X_WB.linear().cwiseAbs() * vehicle_half_m;
  }
};

CollisionWorld::CollisionWorld(const Warehouse& warehouse, const Eigen::Vector3d& vehicle_size_m,
                               double margin_m)
    : impl_(std::make_unique<Impl>()) {
  assert((vehicle_size_m.array() > 0.0).all() && margin_m >= 0.0);
  Impl& w = *impl_;
  w.vehicle_half_m = 0.5 * vehicle_size_m + Eigen::Vector3d::Constant(margin_m);
  w.vehicle_radius_m = w.vehicle_half_m.norm();
  w.vehicle_shape = std::make_unique<btBoxShape>(to_bt(w.vehicle_half_m));
  w.vehicle_shape->setMargin(0.0);
  w.world = std::make_unique<btCollisionWorld>(&w.dispatcher, &w.broadphase, &w.configuration);

  const Eigen::Vector3d& lo = warehouse.arena_min_W_m;
  const Eigen::Vector3d& hi = warehouse.arena_max_W_m;
  w.add_half_space(ElementKind::floor, "floor", Eigen::Vector3d::UnitZ(), 0.0);
  w.add_half_space(ElementKind::wall, "wall x-", Eigen::Vector3d::UnitX(), lo.x());
  w.add_half_space(ElementKind::wall, "wall x+", -Eigen::Vector3d::UnitX(), -hi.x());
  w.add_half_space(ElementKind::wall, "wall y-", Eigen::Vector3d::UnitY(), lo.y());
  w.add_half_space(ElementKind::wall, "wall y+", -Eigen::Vector3d::UnitY(), -hi.y());
  w.add_half_space(ElementKind::wall, "ceiling", -Eigen::Vector3d::UnitZ(), -hi.z());
  for (size_t i = 0; i < warehouse.shelves.size(); ++i) {
    w.add_shelf(static_cast<int>(i), warehouse.shelves[i], warehouse);
  }
}

CollisionWorld::~CollisionWorld() = default;
CollisionWorld::CollisionWorld(CollisionWorld&&) noexcept = default;
CollisionWorld& CollisionWorld::operator=(CollisionWorld&&) noexcept = default;

std::optional<Contact> CollisionWorld::sweep(const Eigen::Isometry3d& X_WB_from, TimeNs t_from_ns,
                                             const Eigen::Isometry3d& X_WB_to, TimeNs t_to_ns,
                                             FloorContacts floor) const {
  std::vector<Contact> c = impl_->sweep(X_WB_from, t_from_ns, X_WB_to, t_to_ns, floor, true);
  if (c.empty()) return std::nullopt;
  return std::move(c.front());
}

std::vector<Contact> CollisionWorld::sweep_all(const Eigen::Isometry3d& X_WB_from,
                                               TimeNs t_from_ns, const Eigen::Isometry3d& X_WB_to,
                                               TimeNs t_to_ns, FloorContacts floor) const {
  return impl_->sweep(X_WB_from, t_from_ns, X_WB_to, t_to_ns, floor, false);
}

std::vector<Contact> CollisionWorld::overlaps(const Eigen::Isometry3d& X_WB, TimeNs t_ns,
                                              FloorContacts floor) const {
  const Eigen::Vector3d half =
      impl_->aabb_half(X_WB) + Eigen::Vector3d::Constant(kContactTolerance_m);
  thread_local std::vector<int> ids;
  impl_->candidates(X_WB.translation() - half, X_WB.translation() + half, floor, true, ids);
  std::vector<Contact> out;
  for (int id : ids) {
    const SignedDistance sd = impl_->distance(X_WB, id);
    if (sd.d < kContactTolerance_m) out.push_back(impl_->make_contact(id, sd, t_ns));
  }
  std::sort(out.begin(), out.end(),
            [](const Contact& x, const Contact& y) { return x.element.id < y.element.id; });
  return out;
}

Clearance CollisionWorld::clearance_to_shelves(const Eigen::Isometry3d& X_WB) const {
  // An element at distance d from the vehicle has its AABB within d of the vehicle's AABB. So
  // search the AABB grown by r; if the nearest part found is within r it is the nearest of all,
  // otherwise grow r. The last round takes every element.
  const Impl& w = *impl_;
  const Eigen::Vector3d half = w.aabb_half(X_WB);
  thread_local std::vector<int> ids;
  Clearance best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (double r = 0.25;; r *= 4.0) {
    const bool last = r > 1e4;
    const Eigen::Vector3d pad = half + Eigen::Vector3d::Constant(last ? 1e9 : r);
    w.candidates(X_WB.translation() - pad, X_WB.translation() + pad, FloorContacts::ignore, false,
                 ids);
    for (int id : ids) {
      const SignedDistance sd = w.distance(X_WB, id);
      if (sd.d < best.distance_m) {
        best = {sd.d, w.elements[static_cast<size_t>(id)], sd.point_on_element_W};
      }
    }
    if (best.distance_m <= r || last) return best;
  }
}

std::optional<RayHit> CollisionWorld::ray_cast(const Eigen::Vector3d& origin_W_m,
                                               const Eigen::Vector3d& direction_W,
                                               double max_range_m) const {
  assert(direction_W.norm() > 0.0 && max_range_m >= 0.0);
  const Impl& w = *impl_;
  const Eigen::Vector3d u = direction_W.normalized();
  const Eigen::Vector3d end = origin_W_m + max_range_m * u;
  thread_local std::vector<int> ids;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(kContactTolerance_m);
  w.candidates(origin_W_m.cwiseMin(end) - pad, origin_W_m.cwiseMax(end) + pad, FloorContacts::report,
               true, ids);
  std::optional<RayHit> best;
  for (int id : ids) {
    const std::optional<double> t = w.ray_parameter(id, origin_W_m, u);
    if (!t || *t > max_range_m) continue;
    const bool closer = !best || *t < best->distance_m || (*t == best->distance_m && id < best->element.id);
    if (closer) best = RayHit{*t, w.elements[static_cast<size_t>(id)], origin_W_m + *t * u};
  }
  return best;
}

double CollisionWorld::distance_to(const Eigen::Isometry3d& X_WB, int element_id) const {
  assert(element_id >= 0 && element_id < static_cast<int>(impl_->elements.size()));
  return impl_->distance(X_WB, element_id).d;
}

const std::vector<Element>& CollisionWorld::elements() const { return impl_->elements; }

const Eigen::Vector3d& CollisionWorld::vehicle_half_extents_m() const {
  return impl_->vehicle_half_m;
}

}  // namespace shelfcross::plant
