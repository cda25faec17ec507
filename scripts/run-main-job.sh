#!/usr/bin/env bash
# Installs what is missing, builds (release preset), and runs the main job. Until the Monte
# Carlo campaign lands, the main job is the open-loop plant demo: take off, hover, fly forward,
# yaw, land; its trajectory goes to out/plant_demo.csv.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
cmake --preset release
cmake --build --preset release
mkdir -p out
./build/release/app/shelfcross plant --commands scenarios/plant_demo.commands --seconds 20 --out out/plant_demo.csv
echo "main job: wrote out/plant_demo.csv"
