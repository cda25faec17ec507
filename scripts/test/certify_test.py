#!/usr/bin/env python3
"""Tests of scripts/certify.sh: what it flies, in which order, with which program.

The program it copies is a small stand-in written here that records its arguments (a real
campaign of 300 runs does not fit a test); what the stand-in checks is the script's own work:
the commands, the copy into OUT and its commit, a failing campaign not stopping the others,
a later call flying OUT's copy.

  python3 scripts/test/certify_test.py
"""
import os
import subprocess
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "certify.sh")


def stand_in(path, mark):
    """A program that appends `mark` and its arguments to calls.txt and fails a search; as
    `tello-sim` it says it is up and writes an empty report, as tello_pilot (`--log`) a log that
    ends."""
    with open(path, "w") as f:
        f.write("#!/bin/sh\n"
                f'echo "{mark} $*" >> calls.txt\n'
                'case "$1" in search) exit 1 ;; tello-sim) echo "renderer: stand-in" ;; esac\n'
                'while [ $# -gt 0 ]; do\n'
                '  case "$1" in\n'
                '    --report) echo "{}" > "$2" ;;\n'
                '    --log) echo \'{"type":"end","t_s":1.0,"outcome":"crossed","reason":"stand-in"}\' > "$2" ;;\n'
                '  esac\n'
                '  shift\n'
                'done\n')
    os.chmod(path, 0o755)


def stand_ins(d, program_mark):
    """Both programs' stand-ins in folder d (the pilot's marked "pilot"), and an OUT there."""
    program, pilot = os.path.join(d, "shelfcross"), os.path.join(d, "tello_pilot")
    stand_in(program, program_mark)
    stand_in(pilot, "pilot")
    return program, pilot, os.path.join(d, "out")


def certify(out, *steps, program=None, pilot=None):
    env = dict(os.environ, JOBS="3")
    if program:
        env["SHELFCROSS"] = program
    if pilot:
        env["TELLO_PILOT"] = pilot
    return subprocess.run(["bash", SCRIPT, out, *steps], env=env, capture_output=True, text=True)


class Certify(unittest.TestCase):
    def test_refuses_an_unknown_step_or_a_missing_program(self):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "out")
            r = certify(out, "table2", "everything", program=os.path.join(d, "none"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("unknown step 'everything'", r.stderr)
            self.assertFalse(os.path.exists(out))
            r = certify(out, "table2", program=os.path.join(d, "none"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("build first", r.stderr)
            program = os.path.join(d, "shelfcross")
            stand_in(program, "first")
            r = certify(out, "table2", program=program, pilot=os.path.join(d, "none"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("build first", r.stderr)

    def test_flies_the_steps_in_order_with_one_copy_of_the_program(self):
        with tempfile.TemporaryDirectory() as d:
            program, pilot, out = stand_ins(d, "first")
            r = certify(out, "table2", "search", "default", program=program, pilot=pilot)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "calls.txt")) as f:
                calls = f.read().splitlines()
            self.assertEqual(calls, [
                "first compare --scenario scenarios/warehouse_5_shelves.yaml --runs 100 --seed 1 --jobs 3 --out table2",
                "first search --scenario scenarios/stress/beyond_gusts.yaml --class near_miss --budget 400 --seed 1"
                " --jobs 3 --out search_beyond_gusts",
                "first campaign --scenario scenarios/paper_test_shelf.yaml --runs 2995 --seed 1 --jobs 3 --out default",
            ])
            self.assertTrue(os.path.isfile(os.path.join(out, "scenarios", "paper_test_shelf.yaml")))
            with open(os.path.join(out, "COMMIT")) as f:
                self.assertRegex(f.read().strip(), r"^[0-9a-f]{7,}(-dirty)?$")
            with open(os.path.join(out, "certify.log")) as f:
                log = f.read()
            self.assertEqual(log.count("start: "), 3)
            self.assertIn("exit 1: search", log)  # the failed search did not stop the default
            self.assertIn("exit 0: campaign --scenario scenarios/paper_test_shelf.yaml", log)

            # The checkout's program changes; the certification goes on with its own copy.
            stand_in(program, "second")
            r = certify(out, "lossy_video", program=program, pilot=pilot)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "calls.txt")) as f:
                last = f.read().splitlines()[-1]
            self.assertEqual(last, "first campaign --scenario scenarios/stress/lossy_video.yaml --runs 300 --seed 7"
                                   " --jobs 3 --out lossy_video")

    def test_the_pilot_step_flies_twenty_flights_once_and_summarises_them(self):
        with tempfile.TemporaryDirectory() as d:
            program, pilot, out = stand_ins(d, "emulator")
            r = certify(out, "pilot", program=program, pilot=pilot)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "calls.txt")) as f:
                calls = f.read().splitlines()
            emulators = [c for c in calls if c.startswith("emulator tello-sim")]
            pilots = [c for c in calls if c.startswith("pilot ")]
            self.assertEqual((len(emulators), len(pilots)), (20, 20))
            self.assertIn("--seed 61 --loss-commands 0.05 --loss-replies 0.05 --loss-state 0.05 --loss-video 0.05",
                          emulators[0])
            self.assertIn("--seed 70 --loss-commands 0.10", emulators[-1])
            self.assertIn("--config flight_sw/config/paper_test_shelf.yaml", pilots[0])
            with open(os.path.join(out, "pilot", "loss_0.10.md")) as f:
                self.assertIn("10 flights: 0 crossed", f.read())
            # Every flight ended: a second call flies none again.
            r = certify(out, "pilot", program=program, pilot=pilot)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "calls.txt")) as f:
                self.assertEqual(len(f.read().splitlines()), 40)


if __name__ == "__main__":
    unittest.main()
