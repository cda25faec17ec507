#pragma once
// The scenario format's one description of every key, walked two ways (scenario.cpp): Reader
// fills the structs from a strict YAML map (file:line errors, absent optional keys keep the
// struct's default), Writer writes them back as YAML in the same order. A section is a
// function template over the visitor, so the format, its defaults and its writer cannot
// drift apart. Internal to scenario/: nothing outside it includes this header.

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "config/strict_yaml.hpp"
#include "shelfcross/warehouse.hpp"
#include "verification/scenario/dispersion_table.hpp"
#include "verification/scenario/distribution.hpp"

namespace shelfcross::verification::scenario_yaml {

using config::Bounds;

enum class Need { optional, required };

template <class T>
Bounds<T> at_least(T lo) {
  Bounds<T> b;
  b.min = lo;
  return b;
}
template <class T>
Bounds<T> between(T lo, T hi) {
  Bounds<T> b;
  b.min = lo;
  b.max = hi;
  return b;
}
inline Bounds<double> above(double lo) {
  Bounds<double> b = at_least(lo);
  b.min_exclusive = true;
  return b;
}

const Bounds<double> kPositive = above(0.0);
const Bounds<double> kNonNegative = at_least(0.0);
const Bounds<double> kUnit = between(0.0, 1.0);
const Bounds<double> kAnyFinite{};

/// The shortest decimal text that reads back to exactly `x`: plain notation ("500", "0.34") in
/// the usual range, else scientific ("1e-300"); at most 17 significant digits either way.
std::string format_double(double x);
/// `s` as a double-quoted YAML scalar.
std::string yaml_quoted(const std::string& s);

/// Well-formed UTF-8 (RFC 3629): no stray continuation or truncated sequence, no overlong
/// form, no surrogate, nothing above U+10FFFF.
bool valid_utf8(const std::string& text);

class Reader {
 public:
  static constexpr bool kReading = true;
  explicit Reader(const config::Map& map) : map_(map) {}

  template <class T>
  void field(const char* key, T& v, const Bounds<T>& b = {}, Need need = Need::optional) const {
    v = need == Need::required ? map_.required<T>(key, b) : map_.optional<T>(key, v, b);
    // Text is written back as YAML, which is UTF-8: other bytes would come back changed
    // (yaml-cpp writes an invalid sequence as U+FFFD), breaking parse(write(s)) == s.
    if constexpr (std::is_same_v<T, std::string>) check(key, valid_utf8(v), "the text is not valid UTF-8");
  }
  void vec3(const char* key, Eigen::Vector3d& v, const Bounds<double>& b = {},
            Need need = Need::optional) const {
    const std::vector<double> l = need == Need::required
                                      ? map_.required_list<double>(key, b, 3)
                                      : map_.optional_list<double>(key, {v.x(), v.y(), v.z()}, b, 3);
    v = {l[0], l[1], l[2]};
  }
  void colour(const char* key, Rgb& c) const {
    const std::vector<double> l = map_.optional_list<double>(key, {c.r, c.g, c.b}, kUnit, 3);
    c = {l[0], l[1], l[2]};
  }
  void list(const char* key, std::vector<double>& v, const Bounds<double>& b, Need need) const {
    v = need == Need::required ? map_.required_list<double>(key, b)
                               : map_.optional_list<double>(key, v, b);
  }
  template <class F>
  void section(const char* key, F&& visit, Need need = Need::optional) const {
    std::optional<config::Map> sub;
    if (need == Need::required) sub.emplace(map_.map(key));
    else sub = map_.optional_map(key);
    if (!sub) return;
    Reader r(*sub);
    visit(r);
    sub->finish();
  }
  /// A list of mappings; `flow` only matters to the writer.
  template <class T, class F>
  void items(const char* key, std::vector<T>& v, F&& visit, Need need, bool /*flow*/) const {
    if (need == Need::optional && !map_.has(key)) {
      map_.optional_map_list(key);  // marks the key as read
      return;
    }
    const std::vector<config::Map> maps = map_.map_list(key);
    v.assign(maps.size(), T{});
    for (size_t i = 0; i < maps.size(); ++i) {
      Reader r(maps[i]);
      visit(r, v[i]);
      maps[i].finish();
    }
  }
  /// The dispersions: a mapping from parameter names (dispersion.hpp) to distributions whose
  /// every draw stays in the parameter's allowed range.
  void distributions(const char* key, std::map<std::string, Distribution>& out) const {
    const std::optional<config::Map> sub = map_.optional_map(key);
    if (!sub) return;
    out.clear();
    for (const DispersionParameter& p : dispersion_parameters()) {
      if (!sub->has(p.name)) continue;
      const Distribution d = parse_distribution(*sub, p.name);
      if (d.lowest() < p.lowest || d.highest() > p.highest) {
        sub->fail(p.name, "its draws can leave the allowed range [" + format_double(p.lowest) + ", " +
                              format_double(p.highest) + "]");
      }
      out[p.name] = d;
    }
    sub->finish();
  }
  /// A consistency rule: refused with the line of `key` when `ok` is false.
  void check(const char* key, bool ok, const std::string& reason) const {
    if (!ok) map_.fail(key, reason);
  }
  const config::Map& map() const { return map_; }

 private:
  const config::Map& map_;
};



class Writer {
 public:
  static constexpr bool kReading = false;
  Writer(std::string& out, int indent, bool dash_first = false, bool flow = false)
      : out_(out), indent_(indent), dash_(dash_first), flow_(flow) {}

  template <class T>
  void field(const char* key, T& v, const Bounds<T>& = {}, Need = Need::optional) {
    if constexpr (std::is_same_v<T, bool>) put(key, v ? "true" : "false");
    else if constexpr (std::is_same_v<T, std::string>) put(key, yaml_quoted(v));
    else if constexpr (std::is_floating_point_v<T>) put(key, format_double(v));
    else put(key, std::to_string(v));
  }
  void vec3(const char* key, Eigen::Vector3d& v, const Bounds<double>& = {}, Need = Need::optional) {
    put(key, flow_list({v.x(), v.y(), v.z()}));
  }
  void colour(const char* key, Rgb& c) { put(key, flow_list({c.r, c.g, c.b})); }
  void list(const char* key, std::vector<double>& v, const Bounds<double>&, Need) {
    put(key, flow_list(v));
  }
  template <class F>
  void section(const char* key, F&& visit, Need = Need::optional) {
    open(key);
    Writer w(out_, indent_ + 2);
    visit(w);
  }
  template <class T, class F>
  void items(const char* key, std::vector<T>& v, F&& visit, Need, bool flow) {
    if (v.empty()) {
      put(key, "[]");
      return;
    }
    open(key);
    for (T& item : v) {
      if (flow) {
        std::string unused;
        Writer w(unused, 0, false, true);
        visit(w, item);
        std::string line = "{";
        for (size_t i = 0; i < w.parts_.size(); ++i) line += (i ? ", " : "") + w.parts_[i];
        out_ += std::string(static_cast<size_t>(indent_ + 2), ' ') + "- " + line + "}\n";
      } else {
        Writer w(out_, indent_ + 4, true);
        visit(w, item);
      }
    }
  }
  void distributions(const char* key, std::map<std::string, Distribution>& m) {
    if (m.empty()) {
      put(key, "{}");
      return;
    }
    open(key);
    Writer w(out_, indent_ + 2);
    for (const auto& [name, d] : m) w.put(name.c_str(), flow_text(d));
  }
  void check(const char*, bool, const std::string&) const {}

 private:
  /// A distribution in the flow form of distribution.hpp, doubles exact.
  static std::string flow_text(const Distribution& d) {
    const auto f = [](double x) { return format_double(x); };
    switch (d.kind) {
      case Distribution::Kind::uniform:
        return "{uniform: {min: " + f(d.min) + ", max: " + f(d.max) + "}}";
      case Distribution::Kind::normal:
        return "{normal: {mean: " + f(d.mean) + ", stddev: " + f(d.stddev) + "}}";
      case Distribution::Kind::truncated_normal:
        return "{truncated_normal: {mean: " + f(d.mean) + ", stddev: " + f(d.stddev) + ", min: " + f(d.min) +
               ", max: " + f(d.max) + "}}";
      case Distribution::Kind::choice:
        return "{choice: {values: " + flow_list(d.values) + ", weights: " + flow_list(d.weights) + "}}";
    }
    return "{}";
  }
  static std::string flow_list(const std::vector<double>& v) {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + format_double(v[i]);
    return s + "]";
  }
  std::string prefix() {
    if (dash_) {
      dash_ = false;
      return std::string(static_cast<size_t>(indent_ - 2), ' ') + "- ";
    }
    return std::string(static_cast<size_t>(indent_), ' ');
  }
  void put(const char* key, const std::string& value) {
    if (flow_) {
      parts_.push_back(std::string(key) + ": " + value);
      return;
    }
    out_ += prefix() + key + ": " + value + "\n";
  }
  void open(const char* key) { out_ += prefix() + key + ":\n"; }

  std::string& out_;
  int indent_;
  bool dash_;
  bool flow_;
  std::vector<std::string> parts_;
};

}  // namespace shelfcross::verification::scenario_yaml
