#!/usr/bin/env python3
"""Tests of scripts/check_docs.py: each rule fails on a small repository that breaks it and passes
on one that keeps it. The broken texts are made here, at run time, so that no file of the
repository holds them.

  python3 scripts/test/check_docs_test.py [BUILD_DIR]
BUILD_DIR (the release build folder) enables the runnable-block tests, which run the real
`shelfcross` program; CTest passes it (CMakeLists.txt, test `docs_check_test`).
"""
import atexit
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
CHECK = os.path.join(HERE, "..", "check_docs.py")
# The release build folder, when given, before unittest reads the command line.
BUILD_DIR = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else None

GOOD_README = "\n".join([
    "# product",
    "",
    "    bash scripts/run-main-job.sh",
    "    bash scripts/run-tests.sh",
    "",
    "The guide: [getting started](docs/guide.md); the default scenario `scenarios/a.yaml`.",
    "",
]) + "\n"
GOOD_GUIDE = "\n".join([
    "# guide",
    "",
    "Back to the [README](../README.md#product), a [web page](https://example.org/x.md),",
    "`scenarios/a.yaml`, `scenarios/FILE.yaml` (a placeholder), `out/campaign/report.md` (an output),",
    "`/usr/bin/time` (not the repository's).",
    "",
    "```",
    "[not a link](nowhere.md) `scenarios/nowhere.yaml` inside a code block",
    "```",
]) + "\n"


def make_repository(files):
    root = tempfile.mkdtemp(prefix="check-docs-test-")
    atexit.register(shutil.rmtree, root, True)
    for name, text in files.items():
        path = os.path.join(root, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            f.write(text)
    return root


def run_check(root, *extra):
    result = subprocess.run([sys.executable, CHECK, "--root", root, *extra],
                            capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def good_files():
    return {"README.md": GOOD_README, "docs/guide.md": GOOD_GUIDE, "scenarios/a.yaml": "name: a\n"}


class StaticChecks(unittest.TestCase):
    def assert_fails_with(self, files, expected):
        code, out = run_check(make_repository(files))
        self.assertEqual(code, 1, out)
        self.assertIn(expected, out)

    def test_a_repository_that_keeps_every_rule_passes(self):
        code, out = run_check(make_repository(good_files()))
        self.assertEqual(code, 0, out)
        self.assertIn("check_docs: 0 findings", out)

    def test_a_broken_relative_link_fails_naming_file_and_line(self):
        files = good_files()
        files["docs/guide.md"] += "See [the results](result.md).\n"
        self.assert_fails_with(files, "docs/guide.md:10: link to a missing file: result.md")

    def test_a_backticked_path_that_does_not_exist_fails(self):
        files = good_files()
        files["docs/guide.md"] += "The scenario `scenarios/b.yaml`.\n"
        self.assert_fails_with(files, "docs/guide.md:10: backticked path does not exist: `scenarios/b.yaml`")

    def test_development_history_fails_in_any_text_file(self):
        words = ["sess" + "ion 12", "Iss" + "ue 7", "bran" + "ch issue20b", "/wo" + "rk/campaigns/x",
                 "/tm" + "p/lat/flight_log.jsonl", "on th" + "is VM", "th" + "is 2-core VM"]
        for word in words:
            with self.subTest(word=word):
                files = good_files()
                files["plant/dynamics.cpp"] = f"// measured in {word}\nint x;\n"
                self.assert_fails_with(files, "plant/dynamics.cpp:1: development history")

    def test_the_issue_fails_and_a_commit_hash_fails_in_code(self):
        for name, text in [("plant/dynamics.cpp", "// Defaults of th" + "e issue\nint x;\n"),
                           ("plant/test/dynamics_test.cpp", "// as flown on comm" + "it 4d31c84\nint x;\n"),
                           ("scenarios/a.yaml", "# measured at comm" + "it bfd468c\nversion: 1\n")]:
            with self.subTest(name=name):
                files = good_files()
                files[name] = text
                self.assert_fails_with(files, f"{name}:1: development history")

    def test_a_page_may_name_the_commit_its_figures_were_measured_on(self):
        files = good_files()
        files["docs/guide.md"] += "Measured on comm" + "it 4d31c84.\n"
        code, out = run_check(make_repository(files))
        self.assertEqual(code, 0, out)

    def test_code_that_names_a_missing_document_fails(self):
        files = good_files()
        files["fuzz/corpus/a.yaml"] = "# The shelf (MET" + "HOD.md section 6) and docs/guid" + "e.md\n"
        self.assert_fails_with(files, "fuzz/corpus/a.yaml:1: names a document that does not exist: METHOD.md")
        code, out = run_check(make_repository(files))
        self.assertNotIn("docs/guide.md", out.replace("fuzz/corpus/a.yaml:1: names a document that does not exist: METHOD.md", ""))

    def test_words_that_only_look_like_history_pass(self):
        files = good_files()
        files["docs/guide.md"] += "Each session of the pilot, the issues it raises, /tmp/ and the VM kind.\n"
        code, out = run_check(make_repository(files))
        self.assertEqual(code, 0, out)

    def test_a_readme_over_its_limit_fails(self):
        files = good_files()
        files["README.md"] = GOOD_README + "line\n" * 120
        self.assert_fails_with(files, "more than 120")

    def test_a_readme_without_the_two_commands_early_fails(self):
        files = good_files()
        files["README.md"] = "# product\n" + "\n" * 45 + GOOD_README
        self.assert_fails_with(files, "`bash scripts/run-main-job.sh` not in its first 40 lines")


@unittest.skipUnless(BUILD_DIR, "needs the release build folder")
class RunnableBlocks(unittest.TestCase):
    def run_blocks(self, page):
        files = good_files()
        files["docs/guide.md"] = page
        return run_check(make_repository(files), "--run-blocks", "--build-dir", BUILD_DIR)

    def test_a_block_with_a_current_command_passes(self):
        code, out = self.run_blocks("<!-- runnable -->\n```bash\nbuild/release/app/shelfcross campaign --help\n```\n")
        self.assertEqual(code, 0, out)
        self.assertIn("1 runnable blocks, 0 failed", out)

    def test_a_block_with_a_stale_flag_fails(self):
        code, out = self.run_blocks(
            "text\n\n<!-- runnable -->\n```bash\nbuild/release/app/shelfcross campaign --scenario "
            "scenarios/a.yaml --runs 1 --no-such-flag 3 --out out/x\n```\n")
        self.assertEqual(code, 1, out)
        self.assertIn("docs/guide.md:4: runnable block failed (exit 2)", out)

    def test_a_marker_without_a_block_is_refused(self):
        code, out = self.run_blocks("<!-- runnable -->\ntext\n")
        self.assertNotEqual(code, 0, out)
        self.assertIn("not followed by a fenced block", out)

    def test_a_block_runs_in_the_cheap_form_its_marker_names(self):
        code, out = self.run_blocks("<!-- runnable: --no-such-flag 3 => --help -->\n```bash\n"
                                    "build/release/app/shelfcross campaign --no-such-flag 3\n```\n")
        self.assertEqual(code, 0, out)
        self.assertIn("1 runnable blocks, 0 failed", out)

    def test_a_cheap_form_that_is_not_in_its_block_is_refused(self):
        code, out = self.run_blocks("<!-- runnable: --runs 2 => --runs 1 -->\n```bash\n"
                                    "build/release/app/shelfcross campaign --help\n```\n")
        self.assertEqual(code, 2, out)
        self.assertIn("docs/guide.md:1: runnable marker's '--runs 2' is not in its block", out)

    def test_a_page_without_runnable_blocks_does_not_pass_silently(self):
        code, out = self.run_blocks("no blocks\n")
        self.assertEqual(code, 1, out)
        self.assertIn("0 runnable blocks", out)


if __name__ == "__main__":
    unittest.main(verbosity=2)
