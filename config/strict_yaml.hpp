#pragma once
// Strict reading of YAML configuration: every problem is refused with file, line and reason.
//
//   auto doc = config::Document::from_file("scenario.yaml");
//   config::Map root = doc.root();
//   double v = root.required<double>("speed_mps", {.min = 0.0, .max = 8.0});
//   int n = root.optional<int>("runs", 100, {.min = 1});
//   config::Map cam = root.map("camera");
//   ...
//   cam.finish();  root.finish();   // refuses keys that were never read (unknown keys)
//
// Errors are ConfigError, whose what() reads "file:line: reason". Lines count from 1.
// A key read with the wrong type ("speed_mps: fast"), a missing required key, a value out of
// its bounds, a sequence of the wrong length and an unknown key are all refused.

#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "config/config_error.hpp"

namespace shelfcross::config {

/// Inclusive bounds unless marked exclusive. Empty bounds accept everything.
template <class T>
struct Bounds {
  std::optional<T> min;
  std::optional<T> max;
  bool min_exclusive = false;
  bool max_exclusive = false;
};

/// One mapping of a document. Remembers which keys were read so finish() can refuse the rest.
/// Every refusal below throws ConfigError ("file:line: reason").
class Map {
 public:
  /// Throws ConfigError when `node` is not a mapping or holds a key twice.
  Map(YAML::Node node, std::shared_ptr<const std::string> file);

  bool has(const std::string& key) const;

  /// Scalars: T is bool, int, std::int64_t, std::uint64_t, double or std::string. Throws
  /// ConfigError on a missing required key, a value of another type or outside `bounds`.
  template <class T>
  T required(const std::string& key, const Bounds<T>& bounds = {}) const;
  template <class T>
  T optional(const std::string& key, const T& fallback, const Bounds<T>& bounds = {}) const;

  /// A sequence of scalars; `size` (if given) is the exact length required. Throws ConfigError
  /// as the scalars do, and on a value that is no list or a list of another length.
  template <class T>
  std::vector<T> required_list(const std::string& key, const Bounds<T>& bounds = {},
                               std::optional<size_t> size = std::nullopt) const;
  template <class T>
  std::vector<T> optional_list(const std::string& key, const std::vector<T>& fallback,
                               const Bounds<T>& bounds = {},
                               std::optional<size_t> size = std::nullopt) const;

  /// A nested mapping (required, or optional: empty when absent). Throws ConfigError on a
  /// missing required one or a value that is no mapping.
  Map map(const std::string& key) const;
  std::optional<Map> optional_map(const std::string& key) const;
  /// A sequence of mappings (required, or empty when absent). Throws ConfigError on a missing
  /// required one or an element that is no mapping.
  std::vector<Map> map_list(const std::string& key) const;
  std::vector<Map> optional_map_list(const std::string& key) const;

  /// Refuse every key of this mapping that was never read, naming it and its line: throws
  /// ConfigError on the first.
  void finish() const;

  /// The line of `key` (or of this mapping when the key is absent), for callers' own checks.
  int line_of(const std::string& key) const;
  int line() const;
  const std::string& file() const { return *file_; }
  /// Always throws ConfigError at `key`'s line (this mapping's when absent): a caller's own
  /// refusal.
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;

 private:
  YAML::Node child(const std::string& key) const;  // marks the key as read
  YAML::Node node_;
  std::shared_ptr<const std::string> file_;
  mutable std::set<std::string> read_;
};

/// A parsed YAML document with its file name for messages.
class Document {
 public:
  /// Throw ConfigError on a file that cannot be read, an empty document or a YAML syntax error
  /// (`name` stands for the file in messages).
  static Document from_file(const std::string& path);
  static Document from_string(const std::string& text, const std::string& name);
  Map root() const;

 private:
  Document(YAML::Node root, std::string file);
  YAML::Node root_;
  std::shared_ptr<const std::string> file_;
};

}  // namespace shelfcross::config
