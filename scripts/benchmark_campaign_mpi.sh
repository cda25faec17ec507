#!/usr/bin/env bash
# Campaign throughput with 1 process and with 2 MPI worker ranks (plus the coordinator, rank 0,
# which only stores), each on one thread, on this machine; and the parallel efficiency
#   E = rate(2 ranks) / (2 x rate(1 process)).
# Also checks that both give the same campaign hash.
#   scripts/benchmark_campaign_mpi.sh [RUNS [SCENARIO]]     (default: 8 runs of the paper scenario)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
runs="${1:-8}"
scenario="${2:-$here/scenarios/paper_test_shelf.yaml}"
program="$here/build/release/app/shelfcross"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # harmless when not root

rate() { sed -n 's/.*(\([0-9]*\) runs per hour).*/\1/p' "$1"; }
hash() { sed -n 's/^campaign hash \([0-9a-f]*\)$/\1/p' "$1"; }

"$program" campaign --scenario "$scenario" --runs "$runs" --seed 1 --jobs 1 --out "$out/one" >"$out/one.log" 2>/dev/null
mpirun -np 3 --oversubscribe --bind-to none --mca btl self,vader \
  "$program" campaign --scenario "$scenario" --runs "$runs" --seed 1 --jobs 1 --out "$out/two" >"$out/two.log" 2>/dev/null

r1="$(rate "$out/one.log")"
r2="$(rate "$out/two.log")"
echo "runs: $runs of $(basename "$scenario")"
echo "1 process (--jobs 1):                     $r1 runs per hour"
echo "2 worker ranks (mpirun -np 3, --jobs 1):  $r2 runs per hour"
awk -v a="$r1" -v b="$r2" 'BEGIN { printf "speed-up %.2f, parallel efficiency %.0f %%\n", b / a, 100 * b / (2 * a) }'
if [ "$(hash "$out/one.log")" = "$(hash "$out/two.log")" ]; then
  echo "campaign hash $(hash "$out/one.log") (the same for both)"
else
  echo "campaign hashes differ: $(hash "$out/one.log") vs $(hash "$out/two.log")" >&2
  exit 1
fi
