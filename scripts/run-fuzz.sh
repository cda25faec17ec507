#!/usr/bin/env bash
# Builds the libFuzzer targets (the `fuzz` preset: clang, ASan + UBSan) and runs each on its
# committed seed corpus. New inputs go to a scratch folder, never into fuzz/corpus/; a crash, a
# sanitizer report or a failed property stops the script with libFuzzer's report and the input
# saved as build/fuzz/artifacts/<target>-crash-<sha1>.
#   scripts/run-fuzz.sh ci [TARGET...]       what CI runs: each target a fixed number of inputs
#                                            from libFuzzer seed 1 (repeatable: see below and
#                                            fuzz/README.md; about 25 s each on CI's 2 cores)
#   scripts/run-fuzz.sh SECONDS [TARGET...]  exploration: SECONDS each, a new random seed each
#                                            time (libFuzzer prints it: "INFO: Seed: N")
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mode="${1:-ci}"
shift || true
[[ "$mode" = ci || "$mode" =~ ^[1-9][0-9]*$ ]] || { echo "usage: scripts/run-fuzz.sh ci|SECONDS [TARGET...]" >&2; exit 2; }
# Inputs per target in CI mode: about 25 s at the rates CI measured (fuzz/README.md).
declare -A ci_runs=([state_record]=800000 [sdk_command]=4000000 [scenario]=25000 [flight_config]=80000
                    [video_receiver]=25000)
# The same seed alone does not give the same run: libFuzzer also steers by compared values, and
# with address-space randomisation those include different pointers each time, and it re-reads
# its corpus folder on a timer. CI mode turns both off (setarch -R, -reload=0) where the
# machine allows it (a container's seccomp profile may refuse setarch -R: then it says so).
no_aslr=()
if [ "$mode" = ci ]; then
  if setarch "$(uname -m)" -R true 2>/dev/null; then
    no_aslr=(setarch "$(uname -m)" -R)
  else
    echo "run-fuzz: setarch -R refused here: address-space randomisation stays on, runs may differ slightly"
  fi
fi
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(state_record sdk_command scenario flight_config video_receiver)
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
mkdir -p build/fuzz/artifacts
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
for t in "${targets[@]}"; do
  if [ "$mode" = ci ]; then
    [ -n "${ci_runs[$t]:-}" ] || { echo "run-fuzz.sh: no CI input count for target $t" >&2; exit 2; }
    budget=(-seed=1 -runs="${ci_runs[$t]}" -reload=0)
    echo "== fuzz: $t, ${ci_runs[$t]} inputs from seed 1, on fuzz/corpus/$t"
  else
    budget=(-max_total_time="$mode")
    echo "== fuzz: $t for $mode s on fuzz/corpus/$t"
  fi
  mkdir -p "$scratch/$t"
  # -rss_limit_mb: every target stays well below it; a leak or a blow-up does not.
  status=0
  "${no_aslr[@]}" build/fuzz/fuzz/"${t}"_fuzz "${budget[@]}" -print_final_stats=1 -rss_limit_mb=2048 \
    -artifact_prefix=build/fuzz/artifacts/"$t"- "$scratch/$t" fuzz/corpus/"$t" >"$scratch/$t.log" 2>&1 || status=$?
  grep -aE "INFO: Seed:|INFO: seed corpus|#[0-9]+[[:space:]]+(INITED|DONE)|stat::(number_of_executed_units|peak_rss)" "$scratch/$t.log" || true
  if [ "$status" -ne 0 ]; then
    tail -n 80 "$scratch/$t.log"
    echo "fuzz: $t found a problem (above; the input is in build/fuzz/artifacts/)"
    exit 1
  fi
done
