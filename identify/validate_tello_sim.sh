#!/usr/bin/env bash
# Validation of `shelfcross identify` against drones of known parameters: tello_pilot flies its
# calibration manoeuvre against `shelfcross tello-sim`, whose autopilot a scenario and a seed
# draw, and identify's intervals are compared with the draws (the emulator's report).
#   identify/validate_tello_sim.sh OUT_DIR SCENARIO LOSS SEED...
# LOSS is the datagram loss on every channel (commands, replies, state, video), e.g. 0 or 0.03.
# Each flight runs in real time (about a minute); run it in the background, niced. Writes
# OUT_DIR/seed_N/{emulator.txt,report.json,pilot.txt,flight_log.jsonl,identify/} and
# OUT_DIR/summary.md (identify/summarize_validation.py). Run from the source root after
# `cmake --build --preset release --target shelfcross tello_pilot` (or with BIN=DIR holding copies
# of both programs). SENSES_BOARD="DISTANCE HEIGHT" flies the senses block too, over the
# scenario's board (tello_pilot --senses-board DISTANCE, identify --board-height HEIGHT): with
# scenarios/calibration/senses_board.yaml, SENSES_BOARD="1.5 0.29". IDENTIFY_OPTS adds options to
# each `identify` (e.g. "--bootstrap 60": fewer refits, faster on a loaded machine).
set -uo pipefail
out=${1:?usage: validate_tello_sim.sh OUT_DIR SCENARIO LOSS SEED...}
scenario=${2:?scenario}
loss=${3:?loss}
shift 3
bin=${BIN:-build/release}  # BIN=DIR: binaries copied aside, so that a rebuild cannot pull them away mid-run
pilot=$bin/flight_sw/tello/pilot/tello_pilot
[[ -x $pilot ]] || pilot=$bin/tello_pilot
shelfcross=$bin/app/shelfcross
[[ -x $shelfcross ]] || shelfcross=$bin/shelfcross
pilot_senses=() identify_senses=()
if [[ -n ${SENSES_BOARD:-} ]]; then
  read -r board_distance board_height <<< "$SENSES_BOARD"
  pilot_senses=(--senses-board "$board_distance")
  identify_senses=(--board-height "$board_height")
fi
mkdir -p "$out"
for seed in "$@"; do
  dir="$out/seed_$seed"
  mkdir -p "$dir"
  base=$((20000 + RANDOM % 20000))
  cmd=$base state=$((base + 1)) video=$((base + 2)) state_src=$((base + 3)) video_src=$((base + 4))
  loss_opts=()
  if [[ $loss != 0 ]]; then
    loss_opts=(--loss-commands "$loss" --loss-replies "$loss" --loss-state "$loss" --loss-video "$loss")
  fi
  "$shelfcross" tello-sim --scenario "$scenario" --seed "$seed" --bind-ip 127.0.0.1 \
    --command-port $cmd --client-state-port $state --client-video-port $video \
    --state-source-port $state_src --video-source-port $video_src --max-seconds 180 \
    --report "$dir/report.json" "${loss_opts[@]}" > "$dir/emulator.txt" 2>&1 &
  emu=$!
  for _ in $(seq 600); do grep -q '^renderer:' "$dir/emulator.txt" 2>/dev/null && break; sleep 0.1; done
  status=0
  "$pilot" --config flight_sw/config/paper_test_shelf.yaml --fly-calibration "${pilot_senses[@]}" \
    --drone-ip 127.0.0.1 --local-ip 127.0.0.1 --command-port $cmd --state-port $state --video-port $video \
    --state-source-port $state_src --video-source-port $video_src \
    --log "$dir/flight_log.jsonl" --inventory "$dir/inventory.json" > "$dir/pilot.txt" 2>&1 || status=$?
  kill -TERM $emu 2>/dev/null || true
  wait $emu 2>/dev/null || true
  echo "seed $seed: tello_pilot exit $status"
  # shellcheck disable=SC2086  # IDENTIFY_OPTS is split into options on purpose
  "$shelfcross" identify --log "$dir/flight_log.jsonl" --scenario "$scenario" --truth "$dir/report.json" "${identify_senses[@]}" \
    ${IDENTIFY_OPTS:-} --out "$dir/identify" > "$dir/identify.txt" 2>&1 || echo "seed $seed: identify failed (see $dir/identify.txt)"
done
python3 "$(dirname "$0")/summarize_validation.py" "$out" "$scenario" > "$out/summary.md"
cat "$out/summary.md"
