#include "render/world_faces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

#include <opencv2/aruco.hpp>

namespace shelfcross::render {
namespace {

// Printed black is not black: ~4 % reflectance; in the sRGB-encoded product texel * colour
// this is about 0.2 of white.
constexpr std::uint8_t kBlackTexel = 51;
// Tags are lit only lightly so that their colour survives the lighting range:
// shade_tag = kTagFlat + (1 - kTagFlat) * shade.
constexpr double kTagFlat = 0.7;
// Albedo of the marker paper.
constexpr double kPaperAlbedo = 0.90;
// The texture coordinates of a face without texture: zeros. (Eigen's default constructor leaves
// a vector's coefficients unset, and copying them would read indeterminate values.)
const std::array<Eigen::Vector2f, 4> kNoTexture{Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero(),
                                                Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()};

double srgb_encode(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

// Builds the faces of the whole static world (lens_mesh.hpp turns them into triangles per frame).
class FaceBuilder {
 public:
  FaceBuilder(const Lighting& lighting, double light_scale)
      : lighting_(lighting), light_scale_(light_scale) {
    light_to_W_ = -lighting.direction_W.normalized();
  }

  // Lambert: ambient + directional * max(0, n . l), l toward the light.
  double shade(const Eigen::Vector3d& n_W) const {
    return lighting_.ambient + lighting_.directional * std::max(0.0, n_W.dot(light_to_W_));
  }
  // The face's 8-bit colour k / 255, k = round(255 srgb): the byte GL writes for it, whether
  // a fragment or a clear (renderer.cpp clears to a room face's colour) writes it.
  Eigen::Vector3f colour(const Rgb& albedo, double shade_factor) const {
    const double k = shade_factor * light_scale_;
    auto byte = [](double linear) {
      return static_cast<float>(std::nearbyint(255.0 * srgb_encode(linear)) / 255.0);
    };
    return {byte(albedo.r * k), byte(albedo.g * k), byte(albedo.b * k)};
  }

  // A quad c0 c1 c2 c3 (in order around its edge), seen from the side n_W points to.
  void face(FaceGroup group, const std::array<Eigen::Vector3d, 4>& c, const Eigen::Vector3d& n_W,
            const Eigen::Vector3f& rgb, const std::array<Eigen::Vector2f, 4>& uv = kNoTexture,
            int solid = -1) {
    MeshFace f;
    f.corners_W_m = c;
    f.normal_W = n_W;
    f.rgb = rgb;
    f.uv = uv;
    f.solid = solid;
    faces_[static_cast<std::size_t>(group)].push_back(f);
  }
  // A new id for the faces of one closed solid (MeshFace::solid).
  int new_solid() { return next_solid_++; }

  // An axis-aligned box [lo, hi] in a frame X_WF: six faces, lit by and seen along their
  // outward normals.
  void cuboid(const Eigen::Isometry3d& X_WF, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
              const Rgb& albedo) {
    const int solid = new_solid();
    for (int axis = 0; axis < 3; ++axis) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        Eigen::Vector3d n_F = Eigen::Vector3d::Zero();
        n_F[axis] = side ? 1.0 : -1.0;
        std::array<Eigen::Vector3d, 4> c;
        const double uv_a[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) {
          Eigen::Vector3d p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[a1] = uv_a[k][0] ? hi[a1] : lo[a1];
          p[a2] = uv_a[k][1] ? hi[a2] : lo[a2];
          c[static_cast<size_t>(k)] = X_WF * p;
        }
        const Eigen::Vector3d n_W = X_WF.linear() * n_F;
        face(kFlatFaces, c, n_W, colour(albedo, shade(n_W)), kNoTexture, solid);
      }
    }
  }

  std::vector<MeshFace>& faces(FaceGroup group) { return faces_[static_cast<std::size_t>(group)]; }

 private:
  Lighting lighting_;
  double light_scale_;
  Eigen::Vector3d light_to_W_;
  std::array<std::vector<MeshFace>, kFaceGroups> faces_;
  int next_solid_ = 0;
};

}  // namespace

WorldFaces build_world_faces(const Warehouse& warehouse, const SceneLayout& layout, double light_scale) {
  // ---- marker atlas: tile 0 white, then one tile per distinct marker ID ----
  const int tile = layout.marker_bits + 2 + 2 * kQuietZoneCells;
  std::map<int, int> tile_of_id;
  for (const MarkerQuad& m : layout.markers) tile_of_id.emplace(m.marker_id, 0);
  int next_tile = 1;
  for (auto& [id, t] : tile_of_id) t = next_tile++;
  const int atlas_w = tile * next_tile;
  cv::Mat atlas_img(tile, atlas_w, CV_8UC1, cv::Scalar(255));
  const cv::Ptr<cv::aruco::Dictionary> dict =
      cv::aruco::getPredefinedDictionary(layout.aruco_dictionary_id);
  for (const auto& [id, t] : tile_of_id) {
    cv::Mat marker;  // one pixel per marker cell, black border one cell wide
    cv::aruco::drawMarker(dict, id, layout.marker_bits + 2, marker, 1);
    cv::Mat dst = atlas_img(cv::Rect(t * tile + kQuietZoneCells, kQuietZoneCells,
                                     layout.marker_bits + 2, layout.marker_bits + 2));
    marker.copyTo(dst);
  }
  atlas_img.setTo(cv::Scalar(kBlackTexel), atlas_img == 0);

  // ---- static world ----
  FaceBuilder mesh(warehouse.lighting, light_scale);
  for (const Cuboid& c : layout.cuboids) {
    const Rgb& albedo = c.kind == Cuboid::Kind::kBox ? warehouse.box_colour : warehouse.bar_colour;
    mesh.cuboid(layout.X_WS[static_cast<size_t>(c.shelf)], c.min_S_m, c.max_S_m, albedo);
  }
  for (const TagQuad& t : layout.tags) {
    mesh.face(kDecalFaces, t.corners_W_m, t.normal_W,
              mesh.colour(warehouse.tag_colour, kTagFlat + (1.0 - kTagFlat) * mesh.shade(t.normal_W)));
    // Tags are coloured on their outer side only: half-way between the tag and the bar, a
    // backing square in the bar colour, facing inward, is what shows from inside the shelf (a
    // tag of the back face seen through the cells from the front is not a tag blob).
    std::array<Eigen::Vector3d, 4> back = t.corners_W_m;
    for (auto& c : back) c -= 0.5 * kSurfaceOffset_m * t.normal_W;
    mesh.face(kFlatFaces, back, -t.normal_W, mesh.colour(warehouse.bar_colour, mesh.shade(-t.normal_W)));
  }
  // Room: floor, ceiling, four walls, as the inside of the arena box (normals inward).
  const Eigen::Vector3d lo = warehouse.arena_min_W_m, hi = warehouse.arena_max_W_m;
  const Eigen::AlignedBox3d arena(lo, hi);
  const int room_solid = mesh.new_solid();
  auto room_face = [&](int axis, bool high, const Rgb& albedo) {
    // One face of the arena box, lit by and seen along its inward normal.
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    std::array<Eigen::Vector3d, 4> c;
    const double uv_a[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d p;
      p[axis] = high ? hi[axis] : lo[axis];
      p[a1] = uv_a[k][0] ? hi[a1] : lo[a1];
      p[a2] = uv_a[k][1] ? hi[a2] : lo[a2];
      c[static_cast<size_t>(k)] = p;
    }
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[axis] = high ? -1.0 : 1.0;
    mesh.face(kRoomFaces, c, n, mesh.colour(albedo, mesh.shade(n)), kNoTexture, room_solid);
  };
  room_face(2, false, warehouse.floor_colour);
  room_face(2, true, warehouse.wall_colour);
  for (int axis : {0, 1})
    for (bool high : {false, true}) room_face(axis, high, warehouse.wall_colour);
  for (const MarkerQuad& m : layout.markers) {
    const float u0 = static_cast<float>(tile_of_id.at(m.marker_id) * tile) / atlas_w;
    const float u1 = static_cast<float>((tile_of_id.at(m.marker_id) + 1) * tile) / atlas_w;
    // Corners TL TR BR BL <- image rows top (v = 0) to bottom (v = 1).
    mesh.face(kTexturedFaces, m.quiet_corners_W_m, m.normal_W,
              mesh.colour({kPaperAlbedo, kPaperAlbedo, kPaperAlbedo}, mesh.shade(m.normal_W)),
              {Eigen::Vector2f(u0, 0.f), Eigen::Vector2f(u1, 0.f), Eigen::Vector2f(u1, 1.f),
               Eigen::Vector2f(u0, 1.f)});
  }
  bool room_first = true;
  for (FaceGroup g : {kFlatFaces, kDecalFaces, kTexturedFaces})
    for (const MeshFace& f : mesh.faces(g))
      for (const Eigen::Vector3d& c : f.corners_W_m) room_first = room_first && arena.contains(c);
  WorldFaces out;
  for (FaceGroup g : {kRoomFaces, kFlatFaces, kDecalFaces, kTexturedFaces})
    out.faces[static_cast<std::size_t>(g)] = std::move(mesh.faces(g));
  out.atlas = atlas_img;
  out.arena = arena;
  out.room_first = room_first;
  return out;
}

}  // namespace shelfcross::render
