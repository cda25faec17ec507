#include "verification/cosim/run_hash.hpp"

#include <cstdio>
#include <stdexcept>

#include <xxhash.h>

namespace shelfcross::verification {

struct RunHasher::State {
  XXH3_state_t* xxh = nullptr;
};

RunHasher::RunHasher() : state_(std::make_unique<State>()) {
  state_->xxh = XXH3_createState();
  if (state_->xxh == nullptr || XXH3_128bits_reset(state_->xxh) == XXH_ERROR) {
    throw std::runtime_error("RunHasher: cannot initialise XXH3 state");
  }
}

RunHasher::~RunHasher() { XXH3_freeState(state_->xxh); }

void RunHasher::add_bytes(const void* data, size_t size) {
  XXH3_128bits_update(state_->xxh, data, size);
}

std::string RunHasher::hex() const {
  const XXH128_hash_t digest = XXH3_128bits_digest(state_->xxh);
  char text[33];
  std::snprintf(text, sizeof(text), "%016llx%016llx", static_cast<unsigned long long>(digest.high64),
                static_cast<unsigned long long>(digest.low64));
  return text;
}

}  // namespace shelfcross::verification
