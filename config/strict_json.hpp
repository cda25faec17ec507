#pragma once
// Strict reading of the JSON that shelfcross writes itself (run metrics, campaign summaries):
// each key read once with its type, and finish() refuses every key nobody asked for. Errors
// are std::invalid_argument: "<what>: '<key path>': <reason>", e.g.
// "run metrics: 'link.frames_lost': expected an integer".

#include <cstdint>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace shelfcross::config {

/// The writer's side of StrictObject::optional_number: the number, or null when there is none.
inline nlohmann::json number_or_null(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

class StrictObject {
 public:
  using json = nlohmann::json;

  /// `what` names the document in errors; `path` prefixes the keys ("link." inside "link").
  StrictObject(const json& j, std::string what, std::string path = "")
      : j_(j), what_(std::move(what)), path_(std::move(path)) {
    if (!j_.is_object()) fail_at(path_.empty() ? "(top)" : path_.substr(0, path_.size() - 1), "expected an object");
  }

  const json& at(const std::string& key) {
    used_.insert(key);
    const auto it = j_.find(key);
    if (it == j_.end()) fail_at(path_ + key, "missing");
    return *it;
  }
  bool has(const std::string& key) const { return j_.contains(key); }

  double number(const std::string& key) {
    const json& v = at(key);
    if (!v.is_number()) fail_at(path_ + key, "expected a number");
    return v.get<double>();
  }
  std::optional<double> optional_number(const std::string& key) {
    const json& v = at(key);
    if (v.is_null()) return std::nullopt;
    if (!v.is_number()) fail_at(path_ + key, "expected a number or null");
    return v.get<double>();
  }
  std::int64_t integer(const std::string& key) {
    const json& v = at(key);
    if (!v.is_number_integer()) fail_at(path_ + key, "expected an integer");
    return v.get<std::int64_t>();
  }
  bool boolean(const std::string& key) {
    const json& v = at(key);
    if (!v.is_boolean()) fail_at(path_ + key, "expected true or false");
    return v.get<bool>();
  }
  std::string text(const std::string& key) {
    const json& v = at(key);
    if (!v.is_string()) fail_at(path_ + key, "expected a string");
    return v.get<std::string>();
  }
  /// The object at `key`, or nullopt when it is null.
  std::optional<StrictObject> optional_object(const std::string& key) {
    const json& v = at(key);
    if (v.is_null()) return std::nullopt;
    return StrictObject(v, what_, path_ + key + ".");
  }
  StrictObject object(const std::string& key) { return StrictObject(at(key), what_, path_ + key + "."); }
  /// Every key of this object, each marked as read (for maps keyed by name).
  std::set<std::string> keys() {
    std::set<std::string> k;
    for (const auto& [key, value] : j_.items()) {
      k.insert(key);
      used_.insert(key);
    }
    return k;
  }

  void finish() const {
    for (const auto& [key, value] : j_.items()) {
      if (!used_.count(key)) fail_at(path_ + key, "unknown key");
    }
  }

  [[noreturn]] void fail_at(const std::string& key_path, const std::string& why) const {
    throw std::invalid_argument(what_ + ": '" + key_path + "': " + why);
  }
  /// The key path of `key` in this object, for callers' own errors.
  std::string path_of(const std::string& key) const { return path_ + key; }

 private:
  const json& j_;
  std::string what_;
  std::string path_;
  std::set<std::string> used_;
};

}  // namespace shelfcross::config
