#pragma once
// Combining the databases of a campaign's shards (`campaign --shard I/N`, e.g. one per task of
// a Slurm job array) into one, which then holds what a single process would have stored: the
// same runs, the same run hashes, the same campaign hash.

#include <cstdint>
#include <filesystem>
#include <vector>

namespace shelfcross::verification {

struct MergeCounts {
  std::int64_t added = 0;       ///< runs copied into the target
  std::int64_t duplicates = 0;  ///< runs the target already held, with the same run hash
};

/// Copies every run of the databases `sources` into `target` (created if absent, with the
/// sources' campaign; runs_requested the largest of theirs). Every source (and an existing
/// target) must be the same scenario and seed, else ResultsMismatch. A run index stored twice
/// must have the same run hash (same scenario, seed and index give the same run); differing
/// hashes mean the builds that made them disagree, and are refused: throws ResultsMismatch
/// (so on no source, or a source of another campaign).
/// Every check comes before the runs are written, in one transaction: on any error, no run is
/// added to the target.
MergeCounts merge_campaigns(const std::vector<std::filesystem::path>& sources, const std::filesystem::path& target);

}  // namespace shelfcross::verification
