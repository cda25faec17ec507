#!/usr/bin/env bash
# Flies the certification: every campaign whose figures the results page (docs/results.md)
# carries, on one build, into one folder, resumable step by step.
#
#   bash scripts/certify.sh OUT [STEP ...]
#
# STEP: table2, lossy_video, stress, beyond, search, default (all of them, in this order, when
# none is named). The first call copies build/release/app/shelfcross and the scenarios into OUT
# with the commit they were built from (OUT/COMMIT); every later call flies OUT's copy, so a
# campaign is never mixed across two programs. Each campaign resumes where it stopped (a
# finished run is never flown again); OUT/certify.log says what ran, when and how it ended.
# JOBS (default: every core) sets the workers; SHELFCROSS the program to copy (default
# build/release/app/shelfcross).
#
# What each step must show: docs/campaigns.md, "The certification"; what each cost: the
# results page.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
all_steps=(table2 lossy_video stress beyond search default)
[ $# -ge 1 ] || { echo "usage: bash scripts/certify.sh OUT [${all_steps[*]} ...]" >&2; exit 2; }
out="$1"; shift
steps=("$@")
[ ${#steps[@]} -gt 0 ] || steps=("${all_steps[@]}")
for s in "${steps[@]}"; do
  [[ " ${all_steps[*]} " == *" $s "* ]] || { echo "certify: unknown step '$s'" >&2; exit 2; }
done
jobs="${JOBS:-$(nproc)}"
program="${SHELFCROSS:-$root/build/release/app/shelfcross}"

mkdir -p "$out"
cd "$out"
if [ ! -x shelfcross ]; then
  [ -x "$program" ] || { echo "certify: no program at $program: build first (cmake --build --preset release)" >&2; exit 2; }
  cp "$program" shelfcross
  cp -r "$root/scenarios" scenarios
  git -C "$root" describe --always --dirty > COMMIT
fi
echo "certify: flying $(cat COMMIT)'s program in $(pwd)"

fly() {
  echo "== $(date -u +%FT%TZ) start: $*" >> certify.log
  local rc=0
  ./shelfcross "$@" || rc=$?
  echo "== $(date -u +%FT%TZ) exit $rc: $*" >> certify.log
}

for s in "${steps[@]}"; do
  case "$s" in
    table2)
      fly compare --scenario scenarios/warehouse_5_shelves.yaml --runs 100 --seed 1 --jobs "$jobs" --out table2 ;;
    lossy_video)
      fly campaign --scenario scenarios/stress/lossy_video.yaml --runs 300 --seed 7 --jobs "$jobs" --out lossy_video ;;
    stress)
      for f in grid_6x6_mixed row_shelf_behind grid_2x2 dim_uneven_light grid_5x3_yellow grid_3x5_magenta_far; do
        fly campaign --scenario "scenarios/stress/$f.yaml" --runs 300 --seed 1 --jobs "$jobs" --out "$f"
      done ;;
    beyond)
      for f in beyond_gusts beyond_drafts beyond_autopilot beyond_calibration beyond_link; do
        fly campaign --scenario "scenarios/stress/$f.yaml" --runs 300 --seed 1 --jobs "$jobs" --out "$f"
      done ;;
    search)
      fly search --scenario scenarios/stress/beyond_gusts.yaml --class contact --budget 400 --seed 1 \
        --jobs "$jobs" --out search_beyond_gusts ;;
    default)
      fly campaign --scenario scenarios/paper_test_shelf.yaml --runs 2995 --seed 1 --jobs "$jobs" --out default ;;
  esac
done
echo "certify: done; $(pwd)/certify.log lists each campaign's exit status"
