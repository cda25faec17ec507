#!/usr/bin/env bash
# Installs what is missing, builds (release preset), and runs every test with CTest, then the
# sanitized tests and the fuzz targets. It ends with the ten slowest tests of each CTest stage
# (CTest's own timing, scripts/slowest_tests.py), so that a test growing slower shows; what
# each stage costs on a 2-core machine is in docs/getting-started.md.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
slowest() {
  if [ -n "${flights_pid:-}" ]; then flights_done || true; fi
  echo
  for junit in build/release/ctest-junit.xml build/release/ctest-junit-flights.xml build/fuzz/ctest-junit.xml \
               build/debug/ctest-junit.xml; do
    if [ -f "$junit" ]; then python3 scripts/slowest_tests.py "$junit"; fi
  done
}
rm -f build/release/ctest-junit.xml build/release/ctest-junit-flights.xml build/fuzz/ctest-junit.xml \
      build/debug/ctest-junit.xml
trap slowest EXIT
cmake --preset release
cmake --build --preset release
# The release suite but its end-to-end flights against the emulator (TelloEndToEnd.*): those are
# paced by the wall clock and use about a fifth of a core, so they fly one after another beside
# the sanitized build below, which has the cores' other four fifths (their log is shown when they
# end). `ctest --preset release -j2` alone runs them beside the other tests.
# One test more than cores: many of the suite's tests wait part of their time (on the programs
# they start, on a stop they time, on an emulator paced by the wall clock), and the one more
# fills those waits (docs/results.md, "Tests and CI").
flights='^TelloEndToEnd\.'
ctest --preset release -j "$(( $(nproc) + 1 ))" -E "$flights"
ctest --preset release -R "$flights" --output-junit ctest-junit-flights.xml > build/release/flights.log 2>&1 &
flights_pid=$!
flights_done() {
  local status=0
  wait "$flights_pid" || status=$?
  flights_pid=
  cat build/release/flights.log
  return "$status"
}
# The parsers' (config, sdk, tello), plant's and flight software's tests under AddressSanitizer
# and UndefinedBehaviorSanitizer, then the parsers under libFuzzer (fuzz/README.md): each target
# a fixed number of inputs from a fixed seed on its corpus (about 25 s each). One clang build
# (the fuzz preset: the sanitizers and libFuzzer's coverage on everything it compiles) compiles
# these libraries once for both. Only these tests: the sanitized build of the rest (render,
# verification, app) would not fit CI's time (the whole suite under the sanitizers:
# docs/getting-started.md). Without clang or libFuzzer's runtime (scripts/debian-packages.txt
# installs both) GCC builds the same tests (the debug preset) and the fuzz targets are not run.
sanitized_tests=(config_test sdk_test plant_test flight_base_test perception_test navigation_test control_test
                 guidance_test mission_test tello_test)
sanitized_labels='^(config|sdk|plant|flight_sw|tello)$'
if command -v clang++ >/dev/null && compgen -G "/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a" >/dev/null; then
  cmake --preset fuzz
  cmake --build build/fuzz --target "${sanitized_tests[@]}" fuzz
  flights_done
  ctest --preset fuzz -j "$(nproc)" -L "$sanitized_labels"
  bash scripts/run-fuzz.sh ci
else
  echo "run-tests: clang++ or libFuzzer's runtime (libclang-rt-14-dev) missing: the sanitized tests built by GCC (the debug preset), fuzz targets not run"
  cmake --preset debug
  cmake --build build/debug --target "${sanitized_tests[@]}"
  flights_done
  ctest --preset debug -j "$(nproc)" -L "$sanitized_labels"
fi
