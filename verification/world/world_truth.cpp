#include "verification/world/world_truth.hpp"

#include <nlohmann/json.hpp>

#include "config/strict_json.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::verification {

using config::StrictObject;
using nlohmann::json;

namespace {

plant::ElementKind element_kind(const StrictObject& contact, const std::string& name) {
  for (plant::ElementKind k : plant::kElementKinds) {
    if (name == plant::to_string(k)) return k;
  }
  contact.fail_at(contact.path_of("kind"), "unknown element kind \"" + name + "\"");
}

std::optional<plant::Contact> read_contact(StrictObject& parent) {
  auto o = parent.optional_object("contact");
  if (!o) return std::nullopt;
  plant::Contact c;
  c.t_ns = seconds_to_ns(o->number("t_s"));
  c.element.name = o->text("element");
  c.element.kind = element_kind(*o, o->text("kind"));
  const json& p = o->at("point_W_m");
  if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
    o->fail_at(o->path_of("point_W_m"), "expected three numbers");
  }
  c.point_W_m = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
  c.depth_m = o->number("depth_m");
  o->finish();
  return c;
}

}  // namespace

json contact_json(const plant::Contact& c) {
  return {{"t_s", ns_to_seconds(c.t_ns)},
          {"element", c.element.name},
          {"kind", plant::to_string(c.element.kind)},
          {"point_W_m", {c.point_W_m.x(), c.point_W_m.y(), c.point_W_m.z()}},
          {"depth_m", c.depth_m}};
}

json cell_json(const std::optional<CellIndex>& c) {
  return c ? json{{"level", c->level}, {"column", c->column}} : json(nullptr);
}

std::optional<CellIndex> read_cell(StrictObject& parent, const std::string& key) {
  auto o = parent.optional_object(key);
  if (!o) return std::nullopt;
  CellIndex c;
  c.level = static_cast<int>(o->integer("level"));
  c.column = static_cast<int>(o->integer("column"));
  o->finish();
  return c;
}

void write_world_truth(json& j, const WorldTruth& t) {
  j["path_length_m"] = t.path_length_m;
  j["contact"] = t.contact ? contact_json(*t.contact) : json(nullptr);
  j["crossed"] = cell_json(t.crossed);
  j["entry_offset_y_m"] = config::number_or_null(t.entry_offset_y_m);
  j["entry_offset_z_m"] = config::number_or_null(t.entry_offset_z_m);
  j["min_clearance_m"] = config::number_or_null(t.min_clearance_m);
}

WorldTruth read_world_truth(StrictObject& o) {
  WorldTruth t;
  t.path_length_m = o.number("path_length_m");
  t.contact = read_contact(o);
  t.crossed = read_cell(o, "crossed");
  t.entry_offset_y_m = o.optional_number("entry_offset_y_m");
  t.entry_offset_z_m = o.optional_number("entry_offset_z_m");
  t.min_clearance_m = o.optional_number("min_clearance_m");
  return t;
}

}  // namespace shelfcross::verification
