#!/usr/bin/env python3
"""What each tello_pilot flight against tello-sim showed, from the folders that
flight_sw/tello/bench/fly_emulator.sh writes (report.json, flight_log.jsonl, inventory.json):

  python3 scripts/summarize_pilot_flights.py FLIGHT_DIR ...

A line per flight (its outcome and reason, crossed, landed, contact, least clearance, the
inventory against the emulator's truth, the flight's end time against the budget) and the counts
a certification quotes: flights that crossed, took the exact inventory and landed; flights that
ended on their own with a named outcome, and the latest end (seconds since the program started,
so the budget plus start-up and the landing); contacts. Exit 1 when a folder holds
no report or no log (the flight never ran), 2 on a usage error.
"""
import argparse
import json
import os
import sys


def boxes(entries):
    return {(b["id"], b["shelf"], b["level"], b["column"]) for b in entries}


def flight(folder):
    """One flight's facts, or None when it has no report or log."""
    report_path = os.path.join(folder, "report.json")
    log_path = os.path.join(folder, "flight_log.jsonl")
    if not (os.path.exists(report_path) and os.path.exists(log_path)):
        return None
    with open(report_path) as f:
        report = json.load(f)
    end = None
    with open(log_path) as f:
        for line in f:
            entry = json.loads(line)
            if entry.get("type") == "end":
                end = entry
    found = None
    inventory_path = os.path.join(folder, "inventory.json")
    if os.path.exists(inventory_path):
        with open(inventory_path) as f:
            found = boxes(json.load(f).get("boxes", []))
    return {
        "name": os.path.basename(os.path.normpath(folder)),
        "outcome": end["outcome"] if end else "none (no end line: the program did not end on its own)",
        "reason": end["reason"] if end else "",
        "end_s": end["t_s"] if end else None,
        "crossed": bool(report.get("crossed")),
        "landed": bool(report.get("landed")),
        "contact": bool(report.get("contact")),
        "clearance_m": report.get("min_clearance_m"),
        "exact_inventory": found is not None and found == boxes(report.get("inventory_truth", [])),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+")
    a = parser.parse_args()
    flights, missing = [], []
    for folder in a.folders:
        f = flight(folder)
        (flights.append(f) if f else missing.append(folder))
    print("| flight | outcome | reason | crossed | exact inventory | landed | contact | least clearance | ended at |")
    print("|---|---|---|---|---|---|---|---|---|")
    for f in flights:
        clearance = "-" if f["clearance_m"] is None else f"{100 * f['clearance_m']:.1f} cm"
        ended = "-" if f["end_s"] is None else f"{f['end_s']:.1f} s"
        print(f"| {f['name']} | {f['outcome']} | {f['reason']} | {'yes' if f['crossed'] else 'no'} | "
              f"{'yes' if f['exact_inventory'] else 'no'} | {'yes' if f['landed'] else 'no'} | "
              f"{'**yes**' if f['contact'] else 'no'} | {clearance} | {ended} |")
    n = len(flights)
    whole = sum(f["crossed"] and f["exact_inventory"] and f["landed"] for f in flights)
    named = [f for f in flights if f["end_s"] is not None and f["outcome"] != "running"]
    latest = max((f["end_s"] for f in named), default=0.0)
    print()
    print(f"{n} flights: {whole} crossed, took the exact inventory and landed; "
          f"{sum(f['exact_inventory'] for f in flights)} took the exact inventory; "
          f"{len(named)} ended on their own with a named outcome (the latest {latest:.1f} s after its start); "
          f"{sum(f['contact'] for f in flights)} contacts")
    for folder in missing:
        print(f"summarize_pilot_flights: {folder}: no report.json or flight_log.jsonl", file=sys.stderr)
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
