#include "flight_sw/perception/inventory.hpp"

#include <cassert>

namespace shelfcross::flight_sw {

Inventory::Inventory(int shelf_index, int levels, int columns, int min_agreeing_frames)
    : shelf_(shelf_index),
      levels_(levels),
      columns_(columns),
      min_agreeing_(min_agreeing_frames),
      counts_(static_cast<size_t>(levels * columns)),
      whole_views_(static_cast<size_t>(levels * columns), 0) {
  assert(levels > 0 && columns > 0 && min_agreeing_frames >= 1);
}

size_t Inventory::slot(CellIndex c) const {
  assert(c.level >= 1 && c.level <= levels_ && c.column >= 1 && c.column <= columns_);
  return static_cast<size_t>((c.level - 1) * columns_ + (c.column - 1));
}

void Inventory::observe(const std::vector<std::pair<CellIndex, int>>& sightings, bool whole) {
  ++frames_;
  if (whole) {
    ++whole_frames_;
    for (int& n : whole_views_) ++n;
  }
  for (const auto& [cell, id] : sightings) {
    ++counts_[slot(cell)][id];
  }
}

void Inventory::observe(const std::vector<std::pair<CellIndex, int>>& sightings,
                        const std::vector<CellIndex>& whole_cells) {
  observe(sightings, false);
  for (const CellIndex& cell : whole_cells) ++whole_views_[slot(cell)];
}

bool Inventory::empty_decidable() const {
  for (int l = 1; l <= levels_; ++l) {
    for (int c = 1; c <= columns_; ++c) {
      if (!box_at({l, c}) && whole_views({l, c}) < min_agreeing_) return false;
    }
  }
  return true;
}

std::optional<int> Inventory::box_at(CellIndex cell) const {
  const auto& m = counts_[slot(cell)];
  int best_id = 0, best = 0, second = 0;
  for (const auto& [id, n] : m) {
    if (n > best) {
      second = best;
      best = n;
      best_id = id;
    } else if (n > second) {
      second = n;
    }
  }
  if (best >= min_agreeing_ && best > second) return best_id;
  return std::nullopt;
}

bool Inventory::is_empty(CellIndex cell) const {
  return whole_views(cell) >= min_agreeing_ && counts_[slot(cell)].empty();
}

std::vector<BoxEntry> Inventory::boxes() const {
  std::vector<BoxEntry> out;
  for (int l = 1; l <= levels_; ++l) {
    for (int c = 1; c <= columns_; ++c) {
      if (auto id = box_at({l, c})) out.push_back({*id, shelf_, l, c});
    }
  }
  return out;
}

std::vector<CellIndex> Inventory::empty_cells() const {
  std::vector<CellIndex> out;
  for (int l = 1; l <= levels_; ++l) {
    for (int c = 1; c <= columns_; ++c) {
      if (is_empty({l, c})) out.push_back({l, c});
    }
  }
  return out;
}

std::vector<CellIndex> Inventory::uncertain_cells() const {
  std::vector<CellIndex> out;
  for (int l = 1; l <= levels_; ++l) {
    for (int c = 1; c <= columns_; ++c) {
      if (!is_empty({l, c}) && !box_at({l, c})) out.push_back({l, c});
    }
  }
  return out;
}

std::string Inventory::to_json() const {
  // Only integers and fixed keys: no escaping is ever needed.
  std::string s = "{\"shelf\":" + std::to_string(shelf_) + ",\"levels\":" +
                  std::to_string(levels_) + ",\"columns\":" + std::to_string(columns_) +
                  ",\"frames\":" + std::to_string(frames_) +
                  ",\"whole_frames\":" + std::to_string(whole_frames_) + ",\"boxes\":[";
  const auto bx = boxes();
  for (size_t i = 0; i < bx.size(); ++i) {
    s += (i ? "," : "");
    s += "{\"id\":" + std::to_string(bx[i].id) + ",\"shelf\":" + std::to_string(bx[i].shelf) +
         ",\"level\":" + std::to_string(bx[i].level) +
         ",\"column\":" + std::to_string(bx[i].column) + "}";
  }
  auto cells = [&](const char* key, const std::vector<CellIndex>& v) {
    s += std::string("],\"") + key + "\":[";
    for (size_t i = 0; i < v.size(); ++i) {
      s += (i ? "," : "");
      s += "{\"level\":" + std::to_string(v[i].level) +
           ",\"column\":" + std::to_string(v[i].column) + "}";
    }
  };
  cells("empty", empty_cells());
  cells("uncertain", uncertain_cells());
  s += "]}";
  return s;
}

}  // namespace shelfcross::flight_sw
