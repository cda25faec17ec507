#include "config/strict_yaml.hpp"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <type_traits>

namespace shelfcross::config {
namespace {

int line_of_node(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

template <class T>
const char* type_name() {
  if constexpr (std::is_same_v<T, bool>) return "a boolean (true/false)";
  else if constexpr (std::is_integral_v<T>) return "an integer";
  else if constexpr (std::is_floating_point_v<T>) return "a number";
  else return "a string";
}

// Converts one scalar node, refusing anything that is not exactly of type T.
template <class T>
std::optional<T> convert_scalar(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  const std::string& text = node.Scalar();
  if constexpr (std::is_same_v<T, std::string>) {
    return text;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (text == "true" || text == "True" || text == "TRUE") return true;
    if (text == "false" || text == "False" || text == "FALSE") return false;
    return std::nullopt;
  } else {
    // yaml-cpp's own conversion accepts the YAML number forms; it refuses trailing text.
    T value{};
    if (!YAML::convert<T>::decode(node, value)) return std::nullopt;
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) return std::nullopt;
    }
    return value;
  }
}

template <class T>
std::string to_text(const T& v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

template <class T>
std::optional<std::string> bounds_violation(const T& value, const Bounds<T>& b) {
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    if (b.min && (b.min_exclusive ? !(value > *b.min) : !(value >= *b.min))) {
      return "value " + to_text(value) + " is out of range: must be " +
             (b.min_exclusive ? "> " : ">= ") + to_text(*b.min);
    }
    if (b.max && (b.max_exclusive ? !(value < *b.max) : !(value <= *b.max))) {
      return "value " + to_text(value) + " is out of range: must be " +
             (b.max_exclusive ? "< " : "<= ") + to_text(*b.max);
    }
  }
  return std::nullopt;
}

}  // namespace

ConfigError::ConfigError(std::string file, int line, std::string reason)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + reason),
      file_(std::move(file)),
      line_(line),
      reason_(std::move(reason)) {}

Map::Map(YAML::Node node, std::shared_ptr<const std::string> file)
    : node_(std::move(node)), file_(std::move(file)) {
  if (!node_.IsMap()) {
    throw ConfigError(*file_, line_of_node(node_), "expected a mapping of keys to values");
  }
  // A key given twice: yaml-cpp keeps both pairs and a lookup sees only the first, so one of
  // the two values would be silently ignored. Refused at the second, naming the first.
  std::map<std::string, int> first_line;
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) continue;
    const auto [at, inserted] = first_line.emplace(kv.first.Scalar(), line_of_node(kv.first));
    if (!inserted) {
      throw ConfigError(*file_, line_of_node(kv.first),
                        "key '" + kv.first.Scalar() + "' given twice (first on line " + std::to_string(at->second) + ")");
    }
  }
}

bool Map::has(const std::string& key) const { return static_cast<bool>(node_[key]); }

YAML::Node Map::child(const std::string& key) const {
  read_.insert(key);
  return node_[key];
}

int Map::line() const { return line_of_node(node_); }

int Map::line_of(const std::string& key) const {
  // The line where the key is written; the mapping's own line when the key is absent.
  for (const auto& kv : node_) {
    if (kv.first.IsScalar() && kv.first.Scalar() == key) return line_of_node(kv.first);
  }
  return line();
}

void Map::fail(const std::string& key, const std::string& reason) const {
  throw ConfigError(*file_, line_of(key), "'" + key + "': " + reason);
}

template <class T>
T Map::required(const std::string& key, const Bounds<T>& bounds) const {
  const YAML::Node n = child(key);
  if (!n) throw ConfigError(*file_, line(), "missing required key '" + key + "'");
  const std::optional<T> value = convert_scalar<T>(n);
  if (!value) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': expected " + type_name<T>());
  }
  if (auto why = bounds_violation(*value, bounds)) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': " + *why);
  }
  return *value;
}

template <class T>
T Map::optional(const std::string& key, const T& fallback, const Bounds<T>& bounds) const {
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  return required<T>(key, bounds);
}

template <class T>
std::vector<T> Map::required_list(const std::string& key, const Bounds<T>& bounds,
                                  std::optional<size_t> size) const {
  const YAML::Node n = child(key);
  if (!n) throw ConfigError(*file_, line(), "missing required key '" + key + "'");
  if (!n.IsSequence()) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': expected a list");
  }
  if (size && n.size() != *size) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': expected a list of " +
                                                    std::to_string(*size) + " values, got " +
                                                    std::to_string(n.size()));
  }
  std::vector<T> out;
  out.reserve(n.size());
  for (size_t i = 0; i < n.size(); ++i) {
    const YAML::Node e = n[i];
    const std::optional<T> value = convert_scalar<T>(e);
    const std::string where = "'" + key + "' item " + std::to_string(i + 1) + ": ";
    if (!value) throw ConfigError(*file_, line_of_node(e), where + "expected " + type_name<T>());
    if (auto why = bounds_violation(*value, bounds)) {
      throw ConfigError(*file_, line_of_node(e), where + *why);
    }
    out.push_back(*value);
  }
  return out;
}

template <class T>
std::vector<T> Map::optional_list(const std::string& key, const std::vector<T>& fallback,
                                  const Bounds<T>& bounds, std::optional<size_t> size) const {
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  return required_list<T>(key, bounds, size);
}

Map Map::map(const std::string& key) const {
  const YAML::Node n = child(key);
  if (!n) throw ConfigError(*file_, line(), "missing required section '" + key + "'");
  if (!n.IsMap()) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': expected a mapping");
  }
  return Map(n, file_);
}

std::optional<Map> Map::optional_map(const std::string& key) const {
  if (!has(key)) {
    read_.insert(key);
    return std::nullopt;
  }
  return map(key);
}

std::vector<Map> Map::map_list(const std::string& key) const {
  const YAML::Node n = child(key);
  if (!n) throw ConfigError(*file_, line(), "missing required key '" + key + "'");
  if (!n.IsSequence()) {
    throw ConfigError(*file_, line_of_node(n), "'" + key + "': expected a list of mappings");
  }
  std::vector<Map> out;
  for (size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsMap()) {
      throw ConfigError(*file_, line_of_node(n[i]),
                        "'" + key + "' item " + std::to_string(i + 1) + ": expected a mapping");
    }
    out.emplace_back(n[i], file_);
  }
  return out;
}

std::vector<Map> Map::optional_map_list(const std::string& key) const {
  if (!has(key)) {
    read_.insert(key);
    return {};
  }
  return map_list(key);
}

void Map::finish() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string("?");
    if (!read_.count(key)) {
      throw ConfigError(*file_, line_of_node(kv.first), "unknown key '" + key + "'");
    }
  }
}

Document::Document(YAML::Node root, std::string file)
    : root_(std::move(root)), file_(std::make_shared<const std::string>(std::move(file))) {}

Document Document::from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, 0, "cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  return from_string(text.str(), path);
}

Document Document::from_string(const std::string& text, const std::string& name) {
  try {
    YAML::Node root = YAML::Load(text);
    if (!root || root.IsNull()) throw ConfigError(name, 1, "the document is empty");
    return Document(root, name);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(name, e.mark.is_null() ? 0 : e.mark.line + 1, "YAML syntax: " + e.msg);
  }
}

Map Document::root() const { return Map(root_, file_); }

// The scalar types a configuration uses.
#define SHELFCROSS_CONFIG_INSTANTIATE(T)                                                       \
  template T Map::required<T>(const std::string&, const Bounds<T>&) const;                   \
  template T Map::optional<T>(const std::string&, const T&, const Bounds<T>&) const;         \
  template std::vector<T> Map::required_list<T>(const std::string&, const Bounds<T>&,        \
                                                std::optional<size_t>) const;                \
  template std::vector<T> Map::optional_list<T>(const std::string&, const std::vector<T>&,   \
                                                const Bounds<T>&, std::optional<size_t>) const;
SHELFCROSS_CONFIG_INSTANTIATE(bool)
SHELFCROSS_CONFIG_INSTANTIATE(int)
SHELFCROSS_CONFIG_INSTANTIATE(std::int64_t)
SHELFCROSS_CONFIG_INSTANTIATE(std::uint64_t)
SHELFCROSS_CONFIG_INSTANTIATE(double)
SHELFCROSS_CONFIG_INSTANTIATE(std::string)
#undef SHELFCROSS_CONFIG_INSTANTIATE

}  // namespace shelfcross::config
