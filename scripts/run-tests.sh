#!/usr/bin/env bash
# Installs what is missing, builds (release preset), and runs every test with CTest, then the
# sanitized tests and the fuzz targets. It ends with the ten slowest tests of each CTest stage
# (CTest's own timing, scripts/slowest_tests.py), so that a test growing slower shows; what
# each stage costs on a 2-core machine is in docs/getting-started.md.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
slowest() {
  echo
  for junit in build/release/ctest-junit.xml build/debug/ctest-junit.xml; do
    if [ -f "$junit" ]; then python3 scripts/slowest_tests.py "$junit"; fi
  done
}
rm -f build/release/ctest-junit.xml build/debug/ctest-junit.xml
trap slowest EXIT
cmake --preset release
cmake --build --preset release
ctest --preset release -j "$(nproc)"
# The parsers' (config, sdk, tello), plant's and flight software's tests under AddressSanitizer
# and UndefinedBehaviorSanitizer (the debug preset; the whole suite under it: docs/getting-started.md). Only
# these: the debug build of the rest (render, verification, app) would not fit CI's time.
cmake --preset debug
cmake --build build/debug --target config_test sdk_test plant_test flight_base_test perception_test navigation_test \
  control_test guidance_test mission_test tello_test
ctest --preset debug -j "$(nproc)" -L '^(config|sdk|plant|flight_sw|tello)$'
# The parsers under libFuzzer (fuzz/README.md): each target a fixed number of inputs from a
# fixed seed on its corpus (about 25 s each), when clang and libFuzzer's runtime are there
# (scripts/debian-packages.txt installs both).
if command -v clang++ >/dev/null && compgen -G "/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a" >/dev/null; then
  bash scripts/run-fuzz.sh ci
else
  echo "run-tests: clang++ or libFuzzer's runtime (libclang-rt-14-dev) missing: fuzz targets not run"
fi
