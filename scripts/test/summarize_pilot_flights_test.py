#!/usr/bin/env python3
"""Tests of scripts/summarize_pilot_flights.py on flight folders made here.

  python3 scripts/test/summarize_pilot_flights_test.py
"""
import json
import os
import subprocess
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "summarize_pilot_flights.py")
TRUTH = [{"id": 3, "shelf": 0, "level": 1, "column": 1}, {"id": 7, "shelf": 0, "level": 1, "column": 2}]


def flight(root, name, report, end=None, found=None):
    d = os.path.join(root, name)
    os.makedirs(d)
    with open(os.path.join(d, "report.json"), "w") as f:
        json.dump(dict(report, inventory_truth=TRUTH), f)
    with open(os.path.join(d, "flight_log.jsonl"), "w") as f:
        f.write(json.dumps({"type": "start", "t_s": 0.0}) + "\n")
        if end:
            f.write(json.dumps(dict(end, type="end")) + "\n")
    if found is not None:
        with open(os.path.join(d, "inventory.json"), "w") as f:
            json.dump({"boxes": found}, f)
    return d


class SummarizePilotFlights(unittest.TestCase):
    def test_counts_whole_missions_named_endings_and_contacts(self):
        with tempfile.TemporaryDirectory() as d:
            a = flight(d, "seed_1", {"crossed": True, "landed": True, "contact": False, "min_clearance_m": 0.071},
                       {"t_s": 96.5, "outcome": "crossed", "reason": "crossed cell L2 C2"}, TRUTH)
            b = flight(d, "seed_2", {"crossed": False, "landed": True, "contact": False, "min_clearance_m": 0.5},
                       {"t_s": 121.0, "outcome": "aborted", "reason": "mission time limit"}, TRUTH[:1])
            c = flight(d, "seed_3", {"crossed": True, "landed": False, "contact": True, "min_clearance_m": 0.0})
            r = subprocess.run(["python3", SCRIPT, a, b, c], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("| seed_1 | crossed | crossed cell L2 C2 | yes | yes | yes | no | 7.1 cm | 96.5 s |", r.stdout)
            self.assertIn("| seed_3 | none (no end line: the program did not end on its own) |", r.stdout)
            self.assertIn("3 flights: 1 crossed, took the exact inventory and landed; 1 took the exact inventory; "
                          "2 ended on their own with a named outcome (the latest 121.0 s after its start); 1 contacts",
                          r.stdout)

    def test_a_folder_without_a_flight_fails(self):
        with tempfile.TemporaryDirectory() as d:
            r = subprocess.run(["python3", SCRIPT, d], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1)
            self.assertIn("no report.json or flight_log.jsonl", r.stderr)


if __name__ == "__main__":
    unittest.main()
