#!/usr/bin/env python3
"""Tests of scripts/include_graph.py on small source trees made here, at run time.

  python3 scripts/test/include_graph_test.py
"""
import contextlib
import io
import importlib.util
import os
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "include_graph.py")
spec = importlib.util.spec_from_file_location("include_graph", SCRIPT)
include_graph = importlib.util.module_from_spec(spec)
spec.loader.exec_module(include_graph)


def tree(files):
    """A temporary source tree holding {path: text}."""
    root = tempfile.mkdtemp()
    for path, text in files.items():
        full = os.path.join(root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w", encoding="utf-8") as f:
            f.write(text)
    return root


def run(root):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = include_graph.main(["--root", root])
    return code, out.getvalue()


class IncludeGraphTest(unittest.TestCase):
    def test_a_layered_tree_is_clean(self):
        code, out = run(tree({
            "plant/a.hpp": "#pragma once\n",
            "plant/a.cpp": '#include "plant/a.hpp"\n',
            "plant/b.hpp": '#include "plant/a.hpp"\n',
            "plant/b.cpp": '#include "plant/b.hpp"\n#include "shelfcross/time.hpp"\n',
            "include/shelfcross/time.hpp": "#pragma once\n",
        }))
        self.assertEqual(code, 0, out)
        self.assertIn("0 cycles, 0 forbidden includes", out)

    def test_sources_that_include_each_others_headers_are_a_cycle(self):
        code, out = run(tree({
            "render/a.hpp": "#pragma once\n",
            "render/a.cpp": '#include "render/a.hpp"\n#include "render/b.hpp"\n',
            "render/b.hpp": "#pragma once\n",
            "render/b.cpp": '#include "render/b.hpp"\n#include "render/a.hpp"\n',
        }))
        self.assertEqual(code, 1)
        self.assertIn("include cycle: render/a <-> render/b", out)

    def test_a_longer_cycle_through_headers_is_found(self):
        code, out = run(tree({
            "verification/cosim/a.hpp": '#include "verification/cosim/b.hpp"\n',
            "verification/cosim/b.hpp": '#include "verification/cosim/c.hpp"\n',
            "verification/cosim/c.cpp": '#include "verification/cosim/a.hpp"\n',
        }))
        self.assertEqual(code, 1)
        self.assertIn("verification/cosim/a <-> verification/cosim/b <-> verification/cosim/c", out)

    def test_rooms_include_only_the_rooms_below_them(self):
        code, out = run(tree({
            "flight_sw/config.hpp": "#pragma once\n",
            "flight_sw/perception/tags.hpp": '#include "flight_sw/config.hpp"\n',
            "flight_sw/guidance/law.hpp": '#include "flight_sw/perception/tags.hpp"\n',
            "flight_sw/mission/unit.hpp": '#include "flight_sw/guidance/law.hpp"\n',
            "flight_sw/tello/driver.cpp": '#include "flight_sw/mission/unit.hpp"\n',
            "verification/campaign/c.hpp": '#include "verification/cosim/r.hpp"\n',
            "verification/cosim/r.hpp": '#include "verification/world/w.hpp"\n',
            "verification/world/w.hpp": "#pragma once\n",
        }))
        self.assertEqual(code, 0, out)

    def test_an_include_that_runs_back_up_the_room_order_is_forbidden(self):
        code, out = run(tree({
            "flight_sw/navigation/pose.hpp": '#include "flight_sw/guidance/law.hpp"\n',
            "flight_sw/guidance/law.hpp": "#pragma once\n",
            "flight_sw/config.cpp": '#include "flight_sw/perception/tags.hpp"\n',
            "flight_sw/perception/tags.hpp": "#pragma once\n",
            "verification/world/w.cpp": '#include "verification/campaign/c.hpp"\n',
            "verification/campaign/c.hpp": "#pragma once\n",
        }))
        self.assertEqual(code, 1)
        self.assertIn("flight_sw/navigation/pose.hpp: includes flight_sw/guidance/law.hpp", out)
        self.assertIn("flight_sw/config.cpp: includes flight_sw/perception/tags.hpp", out)
        self.assertIn("verification/world/w.cpp: includes verification/campaign/c.hpp", out)
        self.assertIn("3 forbidden includes", out)

    def test_a_room_outside_the_order_and_the_simulation_in_flight_are_forbidden(self):
        code, out = run(tree({
            "verification/elsewhere/e.hpp": '#include "verification/world/w.hpp"\n',
            "verification/world/w.hpp": "#pragma once\n",
            "flight_sw/mission/m.cpp": '#include "plant/dynamics.hpp"\n',
            "plant/dynamics.hpp": "#pragma once\n",
        }))
        self.assertEqual(code, 1)
        self.assertIn("verification/elsewhere/ is a room outside verification's documented order", out)
        self.assertIn("flight_sw/mission/m.cpp: includes plant/dynamics.hpp", out)

    def test_tests_are_leaves(self):
        code, out = run(tree({
            "plant/a.hpp": "#pragma once\n",
            "plant/a.cpp": '#include "plant/a.hpp"\n#include "plant/test/helper.hpp"\n',
            "plant/test/helper.hpp": '#include "plant/a.hpp"\n',
        }))
        self.assertEqual(code, 0, out)

    def test_shipped_code_must_not_include_benchmarks(self):
        code, out = run(tree({
            "bench/frames.hpp": "#pragma once\n",
            "app/cmd.cpp": '#include "bench/frames.hpp"\n',
            "bench/bench.cpp": '#include "bench/frames.hpp"\n',
        }))
        self.assertEqual(code, 1)
        self.assertIn("app/cmd.cpp: includes bench/frames.hpp", out)
        self.assertNotIn("bench/bench.cpp:", out)


if __name__ == "__main__":
    unittest.main()
