#!/usr/bin/env python3
"""How fast each run's heading turned when its crossing started, against the clearance it kept.

    python3 scripts/heading_at_commit.py DIR/results.sqlite [--worst N]

From each run's stored trace (the vehicle's true yaw at 10 Hz and the crossing's start,
`trace_json`): the yaw rate over the 0.3 s before the crossing started and the turn over its
first 1.5 s, beside the least clearance to the shelf and the entry offset (`metrics_json`).
Prints the N runs of least clearance, then the least clearance of the runs that started
turning faster and slower than each of a few rates. The crossing flies on the heading it
starts with (docs/method.md section 7, "A still heading"), so a turn at the commit shows as
clearance lost.
"""
import argparse
import bisect
import json
import sqlite3


def crossings(db_path):
    db = sqlite3.connect(f"file:{db_path}?mode=ro", uri=True)
    for index, trace_json, metrics_json in db.execute("select run_index, trace_json, metrics_json from runs"):
        trace, metrics = json.loads(trace_json), json.loads(metrics_json)
        start_s = trace.get("cross_start_s")
        if start_s is None or metrics.get("min_clearance_m") is None:
            continue
        t, yaw = trace["t"], trace["yaw"]
        k = bisect.bisect_left(t, start_s)
        if k < 3 or k + 15 >= len(t):
            continue
        yield {
            "run": index,
            "rate_radps": (yaw[k] - yaw[k - 3]) / (t[k] - t[k - 3]),
            "turn_rad": yaw[k + 15] - yaw[k],
            "clearance_m": metrics["min_clearance_m"],
            "entry_y_m": metrics.get("entry_offset_y_m") or 0.0,
        }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("db", help="a campaign's results.sqlite")
    ap.add_argument("--worst", type=int, default=10, help="runs of least clearance to list")
    args = ap.parse_args()
    runs = sorted(crossings(args.db), key=lambda r: r["clearance_m"])
    if not runs:
        raise SystemExit("no crossing with a trace in " + args.db)
    print("run  yaw rate before (rad/s)  turn after 1.5 s (rad)  clearance (cm)  entry y (cm)")
    for r in runs[: args.worst]:
        print(f"{r['run']:4d}  {r['rate_radps']:+23.3f}  {r['turn_rad']:+22.3f}  {100 * r['clearance_m']:14.2f}"
              f"  {100 * r['entry_y_m']:+12.1f}")
    print(f"\n{len(runs)} crossings")
    for limit in (0.03, 0.05, 0.1):
        fast = [r["clearance_m"] for r in runs if abs(r["rate_radps"]) > limit]
        slow = [r["clearance_m"] for r in runs if abs(r["rate_radps"]) <= limit]
        fast_text = f"least clearance {100 * min(fast):.1f} cm" if fast else "none"
        slow_text = f"{100 * min(slow):.1f} cm" if slow else "none"
        print(f"turning faster than {limit} rad/s: {len(fast)} runs, {fast_text}; the others {slow_text}")


if __name__ == "__main__":
    main()
