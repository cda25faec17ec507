#pragma once
// The fingerprint of a run's log: XXH3-128 (libxxhash) over every logged value's exact bytes,
// fed in log order. Same scenario and seed give the same hash on any worker; any change in
// any logged bit changes it. Not a cryptographic hash: it detects divergence, not tampering.

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>

namespace shelfcross::verification {

class RunHasher {
 public:
  /// Throws std::runtime_error when XXH3's state cannot be made.
  RunHasher();
  ~RunHasher();
  RunHasher(const RunHasher&) = delete;
  RunHasher& operator=(const RunHasher&) = delete;

  void add_bytes(const void* data, size_t size);
  /// Arithmetic values by their object representation (doubles bit for bit).
  template <class T>
    requires std::is_arithmetic_v<T>
  void add(T value) {
    add_bytes(&value, sizeof(value));
  }
  /// Strings with their length first, so ("ab","c") and ("a","bc") differ.
  void add(std::string_view text) {
    add(static_cast<std::uint64_t>(text.size()));
    add_bytes(text.data(), text.size());
  }

  /// 32 lowercase hex digits of the 128-bit digest of everything added so far.
  std::string hex() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// The campaign hash: RunHasher over the run hashes' hex strings in run-index order.
template <class RunHashRange>
std::string combine_run_hashes(const RunHashRange& hashes_in_run_order) {
  RunHasher h;
  for (const auto& hash : hashes_in_run_order) h.add(std::string_view(hash));
  return h.hex();
}

}  // namespace shelfcross::verification
