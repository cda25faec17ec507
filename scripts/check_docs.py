#!/usr/bin/env python3
"""Keeps the repository's documents true and about the product (docs/getting-started.md, "The
documentation check").

  scripts/check_docs.py [--root DIR]
      Static checks over the text files git tracks or would (ls-files --cached --others
      --exclude-standard; every file but build/ and out/ when DIR is not a git
      work tree), exit 1 on any finding, each printed as file:line: reason:
      - words of development history: development sessions, issue numbers, the one issue a
        change was made for, branch names, absolute paths of a development machine (HISTORY
        below), and in every file but the Markdown documents (code, tests, scripts, data) a
        commit by its hash (CODE_HISTORY: a measured figure's page may name the commit it was
        measured on; code says what it does and why);
      - in code, tests, scripts and data, a document of the repository named that does not
        exist: a path under docs/ or an upper-case name at the root (DOC_NAME);
      - Markdown links to relative paths that do not exist, and backticked repository paths
        (`docs/results.md`, `scenarios/stress/grid_2x2.yaml`) that do not exist;
      - README.md longer than README_MAX_LINES, or without the two commands in its first
        README_COMMANDS_WITHIN lines.
  scripts/check_docs.py --root DIR --run-blocks --build-dir BUILD [--only FILE] [--jobs N]
      Runs every command block of the Markdown files marked runnable (a line `<!-- runnable -->`
      right before a fenced block) with bash -euo pipefail, in a scratch folder that mirrors the
      repository (its top-level entries linked) with `build/release` pointing at BUILD, so the
      guide's commands run as a user runs them from the repository root and their outputs stay
      out of the tree. Exit 1 when a block fails; its output is printed. A marker may name the
      cheap form the check runs instead, `<!-- runnable: --runs 2 => --runs 1 -->` (pairs
      separated by `;`, each left side replaced wherever it appears in the block; one that does
      not appear is refused, so the cheap form cannot go stale). Pages run side by side, --jobs
      at a time (default 2), the blocks of a page one after the other.

Python 3 standard library only.
"""
import argparse
import concurrent.futures
import os
import re
import subprocess
import sys
import tempfile

README_MAX_LINES = 120
README_COMMANDS_WITHIN = 40
README_COMMANDS = ("bash scripts/run-main-job.sh", "bash scripts/run-tests.sh")
RUNNABLE_MARKER = "<!-- runnable -->"
# The marker with the cheap form of the block's commands: "<!-- runnable: OLD => NEW; ... -->".
RUNNABLE_CHEAP = re.compile(r"^<!-- runnable:(.*)-->$")

# Development history has no place in the product's files. The patterns are spelled so that
# this file does not match them itself ("[/]", "[ ]").
HISTORY = re.compile(
    r"\bsessions? [0-9]+"             # a development session by its number
    r"|\bissues? [0-9]+\b"            # an issue by its number
    r"|\bthe[ ]issue\b"               # "the" issue a change was made for
    r"|\bbranch[ ]issue"              # a branch named after an issue
    r"|/work[/]"                      # the development machine's work tree
    r"|/tmp/[A-Za-z0-9_]+[/]"         # its scratch folders
    r"|\bthis (2-core )?VM\b",        # the development machine named as such
    re.IGNORECASE)

# In code, tests, scripts and data: a commit by its hash ("commit" and 7 to 40 hex digits).
CODE_HISTORY = re.compile(r"\bcommits?[ ][0-9a-f]{7,40}\b", re.IGNORECASE)
# A document of the repository named in a code, test or data file: a page under docs/ or an
# upper-case name at the root ("docs/method.md", "README.md").
DOC_NAME = re.compile(r"(?<![\w./-])(docs/[A-Za-z0-9_\-/]+\.md|[A-Z][A-Z0-9_]+\.md)\b")

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
CODE_SPAN = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")
FENCE = re.compile(r"^\s*(```|~~~)")
# A backticked path is checked when it looks like one: no spaces, a slash, a file name or a
# folder, and no placeholder (FILE, DIR, <id>, *, ..., $VAR, {a,b}).
PATH_LIKE = re.compile(r"^[A-Za-z0-9_.\-/]+$")
PLACEHOLDER = re.compile(r"(^|/)[A-Z][A-Z0-9_]*([./]|$)|\.\.\.|[*<>{}$?]")


def tracked_files(root):
    """The repository's files, relative to root: git's list when root is a work tree."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z", "--cached", "--others",
                              "--exclude-standard"], check=True,
                             capture_output=True).stdout
        files = [f for f in out.decode("utf-8", "surrogateescape").split("\0") if f]
        if files:
            return sorted(f for f in files if os.path.isfile(os.path.join(root, f)))
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for folder, dirs, names in os.walk(root):
        dirs[:] = [d for d in dirs if d not in (".git", "build", "out")]
        files.extend(os.path.relpath(os.path.join(folder, n), root) for n in names)
    return sorted(files)


def read_text(path):
    """The file's lines, or None for a binary file (a NUL byte in its first 8 KiB, as git -I)."""
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data[:8192]:
        return None
    return data.decode("utf-8", "replace").splitlines()


def markdown_prose(lines):
    """(line number, text) of the lines outside fenced code blocks."""
    inside = False
    for number, line in enumerate(lines, 1):
        if FENCE.match(line):
            inside = not inside
            continue
        if not inside:
            yield number, line


def slug(heading):
    """A heading's anchor as GitHub makes it: lower case, punctuation dropped, spaces to '-'."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(lines):
    return {slug(line.lstrip("#")) for _, line in markdown_prose(lines) if re.match(r"^#{1,6} ", line)}


class Repository:
    def __init__(self, root):
        self.root = root
        self.files = tracked_files(root)
        self.known = set(self.files)
        for f in self.files:  # every folder that holds a tracked file
            parts = f.split("/")
            for i in range(1, len(parts)):
                self.known.add("/".join(parts[:i]))
        self.top_level = {f.split("/")[0] for f in self.files}

    def exists(self, relative):
        return os.path.normpath(relative).replace(os.sep, "/").strip("/") in self.known


def check_history(repo, name, lines, findings):
    in_code = not name.endswith(".md")
    for number, line in enumerate(lines, 1):
        m = HISTORY.search(line) or (CODE_HISTORY.search(line) if in_code else None)
        if m:
            findings.append(f"{name}:{number}: development history or a development machine's "
                            f"path: \"{m.group(0)}\" (describe the product, and a machine by its kind)")


def check_document_names(repo, name, lines, findings):
    """Documents a code, test or data file names (its comments' references) must exist."""
    if name.endswith(".md") or name.startswith("scripts/test/"):
        return
    for number, line in enumerate(lines, 1):
        for m in DOC_NAME.finditer(line):
            if not repo.exists(m.group(1)):
                findings.append(f"{name}:{number}: names a document that does not exist: {m.group(1)}")


def check_links(repo, name, lines, findings):
    here = os.path.dirname(name)
    for number, line in markdown_prose(lines):
        for target in LINK.findall(line):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                continue  # a URL
            path, _, anchor = target.partition("#")
            path = path or os.path.basename(name)  # "#heading": this page
            full = os.path.normpath(os.path.join(here, path))
            if not repo.exists(full):
                findings.append(f"{name}:{number}: link to a missing file: {target}")
            elif anchor and full.endswith(".md"):
                if anchor not in anchors(read_text(os.path.join(repo.root, full)) or []):
                    findings.append(f"{name}:{number}: link to a missing heading: {target}")
        for span in CODE_SPAN.findall(line):
            path = span.split(":", 1)[0].rstrip("/")
            if ("/" not in path or path.startswith("/") or not PATH_LIKE.match(path)
                    or PLACEHOLDER.search(path)):
                continue  # not a path, an absolute one (not the repository's), a placeholder
            first = path.split("/")[0]
            if first in repo.top_level:
                candidate = path
            elif first == ".." or repo.exists(os.path.join(here, first)):
                candidate = os.path.join(here, path)
            else:
                continue  # not a repository path (an output, an option value, a URL part)
            if not repo.exists(candidate):
                findings.append(f"{name}:{number}: backticked path does not exist: `{span}`")


def check_readme(repo, findings):
    if "README.md" not in repo.known:
        findings.append("README.md: missing")
        return
    lines = read_text(os.path.join(repo.root, "README.md")) or []
    if len(lines) > README_MAX_LINES:
        findings.append(f"README.md:{len(lines)}: {len(lines)} lines, more than {README_MAX_LINES}: "
                        "move the detail to the guide in docs/")
    head = "\n".join(lines[:README_COMMANDS_WITHIN])
    for command in README_COMMANDS:
        if command not in head:
            findings.append(f"README.md: `{command}` not in its first {README_COMMANDS_WITHIN} lines")


def static_checks(root):
    repo = Repository(root)
    findings = []
    for name in repo.files:
        lines = read_text(os.path.join(root, name))
        if lines is None:
            continue
        check_history(repo, name, lines, findings)
        check_document_names(repo, name, lines, findings)
        if name.endswith(".md"):
            check_links(repo, name, lines, findings)
    check_readme(repo, findings)
    return findings


def cheap_form(name, number, script, pairs):
    """The block's script with each "OLD => NEW" of the marker's pairs applied."""
    for pair in filter(None, (p.strip() for p in pairs.split(";"))):
        if "=>" not in pair:
            raise ValueError(f"{name}:{number}: runnable marker's pair {pair!r} is not OLD => NEW")
        old, new = (side.strip() for side in pair.split("=>", 1))
        if not old or old not in script:
            raise ValueError(f"{name}:{number}: runnable marker's {old!r} is not in its block")
        script = script.replace(old, new)
    return script


def runnable_blocks(root, name):
    """(line number, script) of each fenced block preceded by the runnable marker, in the cheap
    form the marker names, if any."""
    lines = read_text(os.path.join(root, name)) or []
    blocks, i = [], 0
    while i < len(lines):
        marker = lines[i].strip()
        cheap = RUNNABLE_CHEAP.match(marker)
        if marker == RUNNABLE_MARKER or cheap:
            j = i + 1
            if j >= len(lines) or not FENCE.match(lines[j]):
                raise ValueError(f"{name}:{i + 1}: {RUNNABLE_MARKER} not followed by a fenced block")
            k = j + 1
            while k < len(lines) and not FENCE.match(lines[k]):
                k += 1
            script = "\n".join(lines[j + 1:k]) + "\n"
            if cheap:
                script = cheap_form(name, i + 1, script, cheap.group(1))
            blocks.append((j + 1, script))
            i = k
        i += 1
    return blocks


def run_page(scratch, page, blocks):
    """Runs a page's blocks in order; (what to print, blocks failed)."""
    out, failures = [], 0
    for number, script in blocks:
        out.append(f"== {page}:{number}")
        result = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=scratch,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if result.returncode != 0:
            failures += 1
            out.append(result.stdout[-6000:])
            out.append(f"{page}:{number}: runnable block failed (exit {result.returncode})")
    return "\n".join(out), failures


def run_blocks(root, build_dir, only, jobs=2):
    repo = Repository(root)
    pages = [only] if only else [f for f in repo.files if f.endswith(".md")]
    work = [(page, runnable_blocks(root, page)) for page in pages]  # every marker checked first
    work = [(page, blocks) for page, blocks in work if blocks]
    count = sum(len(blocks) for _, blocks in work)
    failures = 0
    with tempfile.TemporaryDirectory(prefix="shelfcross-docs-") as scratch:
        for entry in sorted(repo.top_level):  # the repository's top level, linked
            if entry != "build":
                os.symlink(os.path.join(os.path.abspath(root), entry), os.path.join(scratch, entry))
        os.makedirs(os.path.join(scratch, "build"))
        os.symlink(os.path.abspath(build_dir), os.path.join(scratch, "build", "release"))
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            runs = [pool.submit(run_page, scratch, page, blocks) for page, blocks in work]
            for run in runs:  # printed in page order, each page's output together
                text, failed = run.result()
                failures += failed
                print(text, flush=True)
    print(f"check_docs: {count} runnable blocks, {failures} failed")
    return 1 if failures or count == 0 else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--run-blocks", action="store_true", help="run the runnable blocks")
    parser.add_argument("--build-dir", help="the release build folder (with --run-blocks)")
    parser.add_argument("--only", help="run the blocks of this page only (relative to the root)")
    parser.add_argument("--jobs", type=int, default=2, help="pages run side by side (with --run-blocks)")
    args = parser.parse_args()
    if args.run_blocks:
        if not args.build_dir:
            parser.error("--run-blocks needs --build-dir")
        try:
            return run_blocks(args.root, args.build_dir, args.only, args.jobs)
        except ValueError as e:
            print(f"check_docs: {e}")
            return 2
    findings = static_checks(args.root)
    for finding in findings:
        print(finding)
    print(f"check_docs: {len(findings)} findings")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
