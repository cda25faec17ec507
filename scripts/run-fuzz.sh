#!/usr/bin/env bash
# Builds the libFuzzer targets (the `fuzz` preset: clang, ASan + UBSan) and runs each on its
# committed seed corpus. New inputs go to a scratch folder, never into fuzz/corpus/; a crash, a
# sanitizer report or a failed property stops the script with libFuzzer's report and the input
# saved as build/fuzz/artifacts/<target>-crash-<sha1>. The targets run side by side, one per
# core (FUZZ_JOBS=N for N at a time).
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
# Longest first (in CI mode video_receiver, then sdk_command, take the most CPU), so that with
# two at a time the last to start is a short one and no core idles long at the end.
[ ${#targets[@]} -gt 0 ] || targets=(video_receiver sdk_command state_record scenario flight_config)
if [ "$mode" = ci ]; then
  for t in "${targets[@]}"; do
    [ -n "${ci_runs[$t]:-}" ] || { echo "run-fuzz.sh: no CI input count for target $t" >&2; exit 2; }
  done
fi
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
mkdir -p build/fuzz/artifacts
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
# One target: its inputs (CI mode) or its time, its own scratch folder and log; exit status of
# libFuzzer. Each target is one single-threaded process (no -jobs/-workers; the video target's
# decoder runs on the calling thread), so `parallel` of them share the cores without changing
# what any of them runs.
fuzz_one() {
  local t="$1" budget
  if [ "$mode" = ci ]; then
    budget=(-seed=1 -runs="${ci_runs[$t]}" -reload=0)
  else
    budget=(-max_total_time="$mode")
  fi
  mkdir -p "$scratch/$t"
  # -rss_limit_mb: every target stays well below it; a leak or a blow-up does not.
  "${no_aslr[@]}" build/fuzz/fuzz/"${t}"_fuzz "${budget[@]}" -print_final_stats=1 -rss_limit_mb=2048 \
    -artifact_prefix=build/fuzz/artifacts/"$t"- "$scratch/$t" fuzz/corpus/"$t" >"$scratch/$t.log" 2>&1
}
# What a finished target prints (its summary, or libFuzzer's report); 1 when it found a problem.
report_one() {
  local t="$1" status="$2"
  if [ "$mode" = ci ]; then
    echo "== fuzz: $t, ${ci_runs[$t]} inputs from seed 1, on fuzz/corpus/$t"
  else
    echo "== fuzz: $t for $mode s on fuzz/corpus/$t"
  fi
  grep -aE "INFO: Seed:|INFO: seed corpus|#[0-9]+[[:space:]]+(INITED|DONE)|stat::(number_of_executed_units|peak_rss)" "$scratch/$t.log" || true
  if [ "$status" -ne 0 ]; then
    tail -n 80 "$scratch/$t.log"
    echo "fuzz: $t found a problem (above; the input is in build/fuzz/artifacts/)"
    return 1
  fi
}
# Targets side by side, one per core (FUZZ_JOBS to change it), each reported as it ends; the
# first finding starts no further target and stops the script once those under way have ended.
parallel="${FUZZ_JOBS:-$(nproc)}"
[[ "$parallel" =~ ^[1-9][0-9]*$ ]] || { echo "run-fuzz.sh: FUZZ_JOBS must be a positive count" >&2; exit 2; }
declare -A target_of=()
next=0
failed=0
while [ "$next" -lt "${#targets[@]}" ] || [ "${#target_of[@]}" -gt 0 ]; do
  while [ "$failed" -eq 0 ] && [ "$next" -lt "${#targets[@]}" ] && [ "${#target_of[@]}" -lt "$parallel" ]; do
    fuzz_one "${targets[$next]}" &
    target_of[$!]="${targets[$next]}"
    next=$((next + 1))
  done
  [ "${#target_of[@]}" -gt 0 ] || break
  status=0
  wait -n -p ended "${!target_of[@]}" || status=$?
  report_one "${target_of[$ended]}" "$status" || failed=1
  unset "target_of[$ended]"
done
exit "$failed"
