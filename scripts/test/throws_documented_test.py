#!/usr/bin/env python3
"""Tests of scripts/throws_documented.py on small sources made here, at run time.

  python3 scripts/test/throws_documented_test.py
"""
import importlib.util
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
spec = importlib.util.spec_from_file_location("throws_documented", os.path.join(HERE, "..", "throws_documented.py"))
throws_documented = importlib.util.module_from_spec(spec)
spec.loader.exec_module(throws_documented)

SOURCE = """#include "x.hpp"
#include <cassert>
#include <stdexcept>
namespace a {
int Parser::parse(int v) {
  if (v < 0) throw std::invalid_argument("negative");
  return v;
}
void Parser::retry() {
  try { parse(1); } catch (...) { throw; }
}
double scale(double k) {
  assert(k > 0.0);
  return 2.0 * k;
}
int Parser::hidden() { throw std::runtime_error("x"); }
}  // namespace a
"""


def findings(header):
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "x.cpp"), "w") as f:
            f.write(SOURCE)
        with open(os.path.join(d, "x.hpp"), "w") as f:
            f.write(header)
        return [line.split(": ", 1)[1] for line in throws_documented.check_file(os.path.join(d, "x.cpp"))]


class ThrowsDocumentedTest(unittest.TestCase):
    def test_undocumented_throw_and_assert_are_found(self):
        header = ("class Parser {\n public:\n  int parse(int v);\n  void retry();\n\n private:\n"
                  "  int hidden();\n};\n\ndouble scale(double k);\n")
        got = findings(header)
        self.assertEqual(len(got), 2, got)
        self.assertTrue(got[0].startswith("parse throws"), got)
        self.assertTrue(got[1].startswith("scale asserts"), got)

    def test_a_comment_that_says_so_satisfies_each(self):
        header = ("class Parser {\n public:\n  /// Throws std::invalid_argument on a negative v.\n  int parse(int v);\n"
                  "  void retry();\n};\n\n/// k must be > 0 (asserted).\ndouble scale(double k);\n")
        self.assertEqual(findings(header), [])

    def test_a_comment_over_a_group_counts_for_each_but_not_past_a_blank_line(self):
        header = ("class Parser {\n public:\n  /// Both throw on bad input.\n  void retry();\n  int parse(int v);\n"
                  "};\n\n/// k must be > 0 (asserted).\n\ndouble scale(double k);\n")
        got = findings(header)
        self.assertEqual(len(got), 1, got)
        self.assertTrue(got[0].startswith("scale asserts"), got)

    def test_a_rethrow_a_private_member_and_a_call_are_not_declarations(self):
        header = ("class Parser {\n public:\n  /// Throws on a negative v.\n  int parse(int v);\n"
                  "  int twice(int v) { return parse(v) + hidden(); }\n  void retry();\n private:\n"
                  "  int hidden();\n};\n/// must be > 0\ndouble scale(double k);\n")
        self.assertEqual(findings(header), [])


if __name__ == "__main__":
    unittest.main()
