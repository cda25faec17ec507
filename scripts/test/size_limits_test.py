#!/usr/bin/env python3
"""Tests of scripts/size_limits.py: what it counts on small sources made here, at run time.

  python3 scripts/test/size_limits_test.py
"""
import importlib.util
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "size_limits.py")
spec = importlib.util.spec_from_file_location("size_limits", SCRIPT)
size_limits = importlib.util.module_from_spec(spec)
spec.loader.exec_module(size_limits)


def scan_text(text):
    with tempfile.NamedTemporaryFile("w", suffix=".cpp", delete=False) as f:
        f.write(text)
    try:
        return size_limits.scan(f.name)
    finally:
        os.unlink(f.name)


class ScanTest(unittest.TestCase):
    def test_function_lines_from_header_to_closing_brace(self):
        body = "\n".join(f"  x += {i};" for i in range(10))
        functions, _ = scan_text("namespace a {\nint f(int x,\n      int y) {\n" + body + "\n  return x;\n}\n}\n")
        self.assertEqual(functions, [("f", 14, 2)])

    def test_lambdas_and_blocks_belong_to_their_function(self):
        text = ("void g() {\n  auto l = [](int a) {\n    return a;\n  };\n"
                "  if (true) {\n    l(1);\n  }\n}\n")
        functions, _ = scan_text(text)
        self.assertEqual(functions, [("g", 8, 1)])

    def test_braces_in_strings_and_comments_do_not_count(self):
        text = 'int h() {\n  // }\n  const char* s = "}{";\n  /* { */\n  return 1;\n}\n'
        functions, _ = scan_text(text)
        self.assertEqual(functions, [("h", 6, 1)])

    def test_class_members_are_data_and_functions(self):
        text = ("class C {\n public:\n  C() : a_(0) {}\n  int get() const { return a_; }\n"
                "  void set(int a);\n  using T = int;\n  struct Inner {\n    int x;\n  };\n"
                " private:\n  int a_;\n  int b_ = 2;\n};\n")
        functions, classes = scan_text(text)
        self.assertIn(("C", 5, 1), classes)  # C(), get, set, a_, b_
        self.assertIn(("Inner", 1, 7), classes)
        self.assertEqual(sorted(name for name, _, _ in functions), ["C", "get"])

    def test_constructor_with_initialiser_list_is_a_function(self):
        functions, _ = scan_text("S::S(int a)\n    : a_(a), b_{a} {\n  go();\n}\n")
        self.assertEqual([(n, lines) for n, lines, _ in functions], [("S::S", 4)])


class ProgramTest(unittest.TestCase):
    def run_on(self, folder, *args):
        return subprocess.run([sys.executable, SCRIPT, *args, folder], capture_output=True, text=True)

    def test_report_mode_exits_0_and_strict_exits_1_when_over(self):
        with tempfile.TemporaryDirectory(dir=os.path.join(HERE, "..", "..")) as d:
            with open(os.path.join(d, "big.cpp"), "w") as f:
                f.write("void big() {\n" + "  step();\n" * 130 + "}\n")
            folder = os.path.relpath(d, os.path.join(HERE, "..", ".."))
            report = self.run_on(folder)
            self.assertEqual(report.returncode, 0)
            self.assertIn("132 lines   " + folder + "/big.cpp:1 big  OVER", report.stdout)
            self.assertEqual(self.run_on(folder, "--strict").returncode, 1)

    def test_missing_folder_is_a_usage_error(self):
        self.assertEqual(self.run_on("no_such_folder").returncode, 2)


if __name__ == "__main__":
    unittest.main()
