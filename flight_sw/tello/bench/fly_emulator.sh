#!/usr/bin/env bash
# One tello_pilot mission against `shelfcross tello-sim` on loopback, as the end-to-end test
# flies it, for measurements by hand:
#   flight_sw/tello/bench/fly_emulator.sh OUT_DIR [tello-sim options...] [-- tello_pilot options...]
# Writes OUT_DIR/{emulator.txt,report.json,pilot.txt,flight_log.jsonl,inventory.json}.
# Run from the source root after `cmake --build --preset release`, or with BIN=DIR holding
# app/shelfcross and flight_sw/tello/pilot/tello_pilot (copies a rebuild cannot pull away);
# SCENARIO and FLIGHT_CONFIG name the emulator's scenario and tello_pilot's configuration
# (default: scenarios/paper_test_shelf.yaml and flight_sw/config/paper_test_shelf.yaml).
# EMU_NICE=N runs the emulator at nice N (it stands in for the drone's own hardware: for latency measurements of tello_pilot
# on a small machine, let the program under test have the CPU first).
set -euo pipefail
out=${1:?usage: fly_emulator.sh OUT_DIR [tello-sim options] [-- tello_pilot options]}
shift
emu_opts=() pilot_opts=()
while [[ $# -gt 0 ]]; do
  if [[ $1 == -- ]]; then shift; pilot_opts=("$@"); break; fi
  emu_opts+=("$1"); shift
done
mkdir -p "$out"
bin=${BIN:-build/release}
scenario=${SCENARIO:-scenarios/paper_test_shelf.yaml}
flight_config=${FLIGHT_CONFIG:-flight_sw/config/paper_test_shelf.yaml}
base=$((20000 + RANDOM % 20000))
cmd=$base state=$((base + 1)) video=$((base + 2)) state_src=$((base + 3)) video_src=$((base + 4))
${EMU_NICE:+nice -n "$EMU_NICE"} "$bin/app/shelfcross" tello-sim --scenario "$scenario" --bind-ip 127.0.0.1 \
  --command-port $cmd --client-state-port $state --client-video-port $video \
  --state-source-port $state_src --video-source-port $video_src --max-seconds 300 \
  --report "$out/report.json" "${emu_opts[@]}" > "$out/emulator.txt" 2>&1 &
emu=$!
for _ in $(seq 600); do grep -q '^renderer:' "$out/emulator.txt" 2>/dev/null && break; sleep 0.1; done
status=0
"$bin/flight_sw/tello/pilot/tello_pilot" --config "$flight_config" \
  --drone-ip 127.0.0.1 --local-ip 127.0.0.1 --command-port $cmd --state-port $state --video-port $video \
  --state-source-port $state_src --video-source-port $video_src \
  --log "$out/flight_log.jsonl" --inventory "$out/inventory.json" "${pilot_opts[@]}" > "$out/pilot.txt" 2>&1 || status=$?
kill -TERM $emu 2>/dev/null || true
wait $emu || true
echo "tello_pilot exit $status"
tail -n 8 "$out/emulator.txt"
exit $status
