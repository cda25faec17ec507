#!/usr/bin/env bash
# Builds the libFuzzer targets (the `fuzz` preset: clang, ASan + UBSan) and runs each on its
# committed seed corpus for SECONDS (default 30: the CI smoke run; fuzz/README.md has the long
# runs). New inputs go to a scratch folder, never into fuzz/corpus/; a crash, a sanitizer
# report or a failed property stops the script with libFuzzer's report and the input saved as
# build/fuzz/artifacts/<target>-crash-<sha1>. Usage: scripts/run-fuzz.sh [SECONDS [TARGET...]]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds="${1:-30}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(state_record sdk_command scenario flight_config video_receiver)
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
mkdir -p build/fuzz/artifacts
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
for t in "${targets[@]}"; do
  echo "== fuzz: $t for ${seconds} s on fuzz/corpus/$t"
  mkdir -p "$scratch/$t"
  # -rss_limit_mb: every target stays well below it; a leak or a blow-up does not.
  status=0
  build/fuzz/fuzz/"${t}"_fuzz -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=2048 \
    -artifact_prefix=build/fuzz/artifacts/"$t"- "$scratch/$t" fuzz/corpus/"$t" >"$scratch/$t.log" 2>&1 || status=$?
  grep -aE "INFO: seed corpus|#[0-9]+[[:space:]]+(INITED|DONE)|stat::(number_of_executed_units|peak_rss)" "$scratch/$t.log" || true
  if [ "$status" -ne 0 ]; then
    tail -n 80 "$scratch/$t.log"
    echo "fuzz: $t found a problem (above; the input is in build/fuzz/artifacts/)"
    exit 1
  fi
done
