#!/usr/bin/env python3
"""Every public function that throws says so, and every precondition it asserts, where it is
declared. A function is public when a header of the same name declares it (`x.cpp` defines
what `x.hpp` declares); it throws when its own body has a `throw EXPR` (a bare `throw;`
rethrows what a callee threw) and asserts when its body calls `assert(`. Its declaration's
comment (the `//` lines above it, up to a blank line, so a comment over a group of
declarations counts for each; or a `///<` after it) must then say so: "throw" for the
first, and "must", "precondition" or "assert" for the second.

  python3 scripts/throws_documented.py [FOLDER ...]

FOLDER defaults to size_limits' CHECKED folders (test/ folders left out). Prints each finding as
`header:line: function ...`; exit 1 when there is one, 2 on a usage error.

A lexical scan (size_limits.scan's function finder, comments and literals blanked): a throw in
a helper the public function calls is not seen, and an overloaded name is satisfied by any of its
declarations' comments.
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import size_limits  # noqa: E402

THROW = re.compile(r"\bthrow\s+[\w:({]")
ASSERT = re.compile(r"\bassert\s*\(")
SAYS_THROWS = re.compile(r"throw", re.I)
SAYS_PRECONDITION = re.compile(r"\bmust\b|precondition|assert", re.I)


def is_call(before):
    """Whether a name preceded by `before` on its line is called there, not declared."""
    b = before.rstrip()
    return bool(b) and (b[-1] in "[(=,!|+-/?{" or re.search(r"\breturn$", b) is not None) and \
        not b.endswith("::")


def private_member(blanked, n):
    """Whether line n of a header lies under a `private:` or `protected:` label of its class
    (the nearest access label or class head above it, at the class's indentation)."""
    indent = len(blanked[n]) - len(blanked[n].lstrip())
    for c in range(n - 1, -1, -1):
        line = blanked[c]
        stripped = line.strip()
        if not stripped:
            continue
        here = len(line) - len(line.lstrip())
        if here < indent:
            label = re.match(r"(public|private|protected)\s*:", stripped)
            if label:
                return label.group(1) != "public"
            if re.match(r"(class|struct)\b", stripped) or stripped.startswith("}"):
                return stripped.startswith("class")  # a class's members are private by default
            if here == 0:
                return False
    return False


def declaration_comments(header_lines, blanked, name):
    """The comment text of each declaration of `name` in a header (the `//` lines above it up to
    a blank line, the declaration's own lines up to its `;` or `{`, a trailing `///<`);
    `blanked` is the header with its comments and literals blanked, line for line."""
    pattern = re.compile(r"(?<![\w:.>])" + re.escape(name) + r"\s*\(")
    found = []
    for n, code in enumerate(blanked):
        m = pattern.search(code)
        if not m or private_member(blanked, n) or is_call(code[:m.start()]):
            continue
        text = []
        c = n - 1
        # Up through the comment, a `template <...>` line, and the declarations grouped under the
        # same comment (no blank line between), to the first blank line.
        while c >= 0 and header_lines[c].strip():
            if header_lines[c].strip().startswith("//"):
                text.append(header_lines[c])
            c -= 1
        e = n
        while e < len(header_lines) and e < n + 8:
            text.append(header_lines[e])
            if re.search(r"[;{]", blanked[e]):
                break
            e += 1
        if e + 1 < len(header_lines) and header_lines[e + 1].strip().startswith("///<"):
            text.append(header_lines[e + 1])
        found.append((n + 1, " ".join(text)))
    return found


def check_file(source):
    """Findings for one .cpp against the header of the same name."""
    header = source[:-4] + ".hpp"
    if not os.path.exists(header):
        return []
    with open(source, encoding="utf-8", errors="replace") as f:
        text = f.read()
    code = size_limits.blank_comments_and_literals(text).split("\n")
    with open(header, encoding="utf-8", errors="replace") as f:
        header_text = f.read()
    header_lines = header_text.split("\n")
    header_blanked = size_limits.blank_comments_and_literals(header_text).split("\n")
    functions, _ = size_limits.scan(source)
    findings = []
    for name, length, start in functions:
        body = "\n".join(code[start - 1:start - 1 + length])
        short = name.split("::")[-1]
        declarations = declaration_comments(header_lines, header_blanked, short)
        if not declarations:
            continue  # not declared in its header: not public
        rel = os.path.relpath(header, size_limits.ROOT)
        line = declarations[0][0]
        if THROW.search(body) and not any(SAYS_THROWS.search(t) for _, t in declarations):
            findings.append(f"{rel}:{line}: {short} throws (its body, {os.path.basename(source)}:{start}) "
                            "and its declaration does not say so")
        if ASSERT.search(body) and not any(SAYS_PRECONDITION.search(t) for _, t in declarations):
            findings.append(f"{rel}:{line}: {short} asserts a precondition (its body, "
                            f"{os.path.basename(source)}:{start}) and its declaration does not state it")
    return findings


def main():
    folders = sys.argv[1:] or size_limits.CHECKED
    findings = []
    for folder in folders:
        paths = size_limits.sources(folder, (".cpp",))
        if paths is None:
            print(f"throws_documented: no folder {folder}", file=sys.stderr)
            return 2
        for p in paths:
            findings += check_file(p)
    for f in findings:
        print(f)
    print(f"throws_documented: {len(findings)} finding(s)")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
