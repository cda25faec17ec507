#!/usr/bin/env python3
"""Summary of identify's validation flights (validate_tello_sim.sh): for every parameter with a
true value, in how many seeds the true value lies in identify's 95 % interval, and the widest
interval against a quarter of the scenario's range.
   summarize_validation.py OUT_DIR SCENARIO [REPORT_FOLDER]   (default: identify)"""
import glob
import json
import os
import sys

out, scenario = sys.argv[1], sys.argv[2]
folder = sys.argv[3] if len(sys.argv) > 3 else "identify"
runs = []
for path in sorted(glob.glob(os.path.join(out, "seed_*", folder, "identify.json")),
                   key=lambda p: int(p.split("seed_")[1].split(os.sep)[0])):
    with open(path) as f:
        runs.append((path.split("seed_")[1].split(os.sep)[0], json.load(f)))
seeds = sorted(glob.glob(os.path.join(out, "seed_*")))
print(f"# identify against tello-sim: {out}\n\nScenario {scenario}; {len(seeds)} flights, {len(runs)} identified.\n")
names = []
for _, j in runs:
    for n, p in j["parameters"].items():
        if "truth" in p and n not in names:
            names.append(n)
print("| parameter | true value within the 95 % interval | widest interval | quarter of the scenario's range |"
      " intervals within a quarter |")
print("|---|---|---|---|---|")
for n in names:
    within = sum(1 for _, j in runs if j["parameters"].get(n, {}).get("within"))
    have = sum(1 for _, j in runs if "truth" in j["parameters"].get(n, {}))
    widths = [j["parameters"][n]["hi"] - j["parameters"][n]["lo"] for _, j in runs if n in j["parameters"]]
    ranges = [j["parameters"][n].get("scenario_range") for _, j in runs if n in j["parameters"]]
    quarter = (ranges[0][1] - ranges[0][0]) / 4 if ranges and ranges[0] else float("nan")
    narrow = sum(1 for w in widths if w <= quarter)
    print(f"| {n} | {within} of {have} | {max(widths):.4f} | {quarter:.4f} | {narrow} of {len(widths)} |")
print("\n| seed | " + " | ".join(names) + " |")
print("|---|" + "---|" * len(names))
for seed, j in runs:
    cells = []
    for n in names:
        p = j["parameters"].get(n)
        if not p:
            cells.append("-")
            continue
        mark = "" if p.get("within") else " **out**"
        cells.append(f"{p['value']:.3f} [{p['lo']:.3f}, {p['hi']:.3f}] true {p['truth']:.3f}{mark}")
    print(f"| {seed} | " + " | ".join(cells) + " |")
outside = [(seed, j.get("outside", [])) for seed, j in runs if j.get("outside")]
if outside:
    print("\nOutside the scenario's draws (identify's envelope verdict):")
    for seed, names_out in outside:
        print(f"- seed {seed}: {', '.join(names_out)}")
