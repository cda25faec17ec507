#!/usr/bin/env bash
# Installs what is missing, builds the `shelfcross` program and what it links (release preset;
# the test command builds the rest), and runs the main job: a default Monte Carlo crossing
# campaign on the paper's test shelf (scenarios/paper_test_shelf.yaml), all cores, resumable;
# its report is out/campaign/report.md (summary.json, results.sqlite beside). RUNS and SEED may
# be set in the environment.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
cmake --preset release
cmake --build --preset release --target shelfcross
./build/release/app/shelfcross campaign --scenario scenarios/paper_test_shelf.yaml \
  --runs "${RUNS:-20}" --seed "${SEED:-1}" --out out/campaign
echo "main job: report in out/campaign/report.md"
