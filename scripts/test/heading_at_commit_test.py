#!/usr/bin/env python3
"""Tests of scripts/heading_at_commit.py on a campaign store made here, at run time.

  python3 scripts/test/heading_at_commit_test.py
"""
import importlib.util
import json
import os
import sqlite3
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "heading_at_commit.py")
spec = importlib.util.spec_from_file_location("heading_at_commit", SCRIPT)
heading_at_commit = importlib.util.module_from_spec(spec)
spec.loader.exec_module(heading_at_commit)


def store(path, runs):
    """runs: (index, yaw rate before the crossing rad/s, crossing start s or None, clearance m)."""
    db = sqlite3.connect(path)
    db.execute("create table runs(run_index integer primary key, trace_json text, metrics_json text)")
    for index, rate, start_s, clearance in runs:
        t = [0.1 * k for k in range(100)]
        yaw = [rate * max(0.0, min(s, 5.0) - 4.0) for s in t]  # turning from 4 s to 5 s, still after
        trace = {"t": t, "yaw": yaw, "cross_start_s": start_s}
        metrics = {"min_clearance_m": clearance, "entry_offset_y_m": 0.01}
        db.execute("insert into runs values (?, ?, ?)", (index, json.dumps(trace), json.dumps(metrics)))
    db.commit()
    db.close()


class HeadingAtCommitTest(unittest.TestCase):
    def test_rate_before_and_turn_after_the_crossing_start(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "results.sqlite")
            store(path, [(0, 0.1, 5.0, 0.03), (1, 0.0, 5.0, 0.09), (2, 0.1, None, 0.05)])
            runs = {r["run"]: r for r in heading_at_commit.crossings(path)}
            self.assertEqual(sorted(runs), [0, 1])  # run 2 never started a crossing
            self.assertAlmostEqual(runs[0]["rate_radps"], 0.1, places=9)
            self.assertAlmostEqual(runs[0]["turn_rad"], 0.0, places=9)  # the turn ended at the start
            self.assertAlmostEqual(runs[1]["rate_radps"], 0.0, places=9)
            self.assertEqual(runs[0]["clearance_m"], 0.03)


if __name__ == "__main__":
    unittest.main()
