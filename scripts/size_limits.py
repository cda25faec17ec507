#!/usr/bin/env python3
"""The size limits that keep the code's rooms livable (docs/design.md): functions under about 120
lines, classes under about 25 members, source files under about 600 lines. Prints the largest
function, class and file of each folder checked and every one over its limit.

  python3 scripts/size_limits.py [--strict] [--top N] [FOLDER ...]

FOLDER defaults to CHECKED, the folders held to the limits (every sub-folder included; test/
folders are not counted; bench/ and fuzz/ are not held to them). Exit 0 in report mode (the default); with --strict, exit 1 when anything is over
its limit. Exit 2 on a usage error (a folder that does not exist).

How it counts (a lexical scan, no compiler): comments, string and character literals are
blanked first; a function is a brace-delimited body whose header ends in a parameter list
(with qualifiers, a trailing return type or a constructor's initialiser list) at namespace or
class scope, measured from the line its header starts on to its closing brace; a class's
members are its data members and member functions declared directly in it (access labels,
`using`, `friend`, `static_assert` and nested types do not count).
"""
import argparse
import os
import re
import sys

FUNCTION_LINES = 120
CLASS_MEMBERS = 25
FILE_LINES = 600

# The folders CTest holds to the limits (`size_limits --strict`): every folder of the product.
CHECKED = ["include", "config", "sdk", "plant", "render", "flight_sw", "verification", "identify", "distributed",
           "app"]

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def blank_comments_and_literals(text):
    """The text with comments, string and character literals replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


CONTROL = re.compile(r"^\s*(?:}\s*)?(?:else\s+)?(if|for|while|switch|catch|do|else|try)\b")
FUNCTION_HEADER = re.compile(
    r"\)\s*(?:const|noexcept(?:\([^)]*\))?|override|final|mutable|&|&&|\s)*"
    r"(?:->\s*[\w:<>,\s*&]+)?\s*$|\)\s*:\s*[\w:]+\s*[({].*$",
    re.S)
CTOR_INIT = re.compile(r"\)\s*:\s*[\w:]+\s*[({]")
TYPE_HEADER = re.compile(r"\b(class|struct|union)\s+(\w+)[^()]*$", re.S)
NAMESPACE_HEADER = re.compile(r'^\s*(namespace\b|extern\s*$|extern\b)', re.S)


def scan(path):
    """(functions, classes) of one file: lists of (name, lines or members, first line)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank_comments_and_literals(f.read())
    # Preprocessor lines do not open or close scopes.
    text = re.sub(r"^[ \t]*#[^\n]*", lambda m: " " * len(m.group(0)), text, flags=re.M)
    functions, classes = [], []
    stack = []  # (kind, name, start line, member count)
    header_start = 0  # index where the current statement or header begins
    line = 1
    header_line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
            continue
        if c not in "{};":
            if text[header_start:i].strip() == "":
                header_line = line
            continue
        header = text[header_start:i]
        in_function = any(k in ("function", "other") for k, *_ in stack)
        top = next((k for k, *_ in reversed(stack) if k != "init"), None)
        if c == "{":
            h = " ".join(header.split())
            before = text[:i].rstrip()[-1:]
            brace_init = (not in_function and before and (before.isalnum() or before in "_>") and
                          not NAMESPACE_HEADER.match(h) and not TYPE_HEADER.search(h) and
                          not re.search(r"\benum\b", h) and ("(" not in h or CTOR_INIT.search(h)))
            if brace_init:
                # A member's brace initialiser (`int b_{2};`, `: b_{a}`): part of the statement.
                stack.append(["init", "", line, 0])
                continue
            if in_function:
                kind = "other"
            elif NAMESPACE_HEADER.match(h):
                kind = "namespace"
            elif TYPE_HEADER.search(h) and "=" not in h:
                kind = "class"
            elif "(" in h and not CONTROL.match(h) and FUNCTION_HEADER.search(h):
                kind = "function"
            elif h.endswith("=") or h == "" or re.search(r"\benum\b", h):
                kind = "other"
            else:
                kind = "other"
            name = ""
            if kind == "class":
                name = TYPE_HEADER.search(h).group(2)
            elif kind == "function":
                m = re.search(r"([\w:~]+(?:<[^()]*>)?|operator\s*[^\s(]+)\s*\((?!.*\)\s*:\s*[\w:]+\s*[({]\s*\w+\s*\()", h)
                name = m.group(1) if m else h[:40]
            if top == "class" and kind == "function":
                next(e for e in reversed(stack) if e[0] != "init")[3] += 1
            stack.append([kind, name, header_line, 0])
        elif c == "}":
            if stack and stack[-1][0] == "init":
                stack.pop()
                continue
            if stack:
                kind, name, start, members = stack.pop()
                if kind == "function":
                    functions.append((name, line - start + 1, start))
                elif kind == "class":
                    classes.append((name, members, start))
        elif c == ";":
            if stack and stack[-1][0] == "class":
                h = " ".join(header.split())
                h = re.sub(r"^(public|private|protected)\s*:\s*", "", h)
                if h and not re.match(r"(using|friend|static_assert|typedef|class|struct|enum|union)\b", h):
                    stack[-1][3] += 1
        header_start = i + 1
        header_line = line
    return functions, classes


def sources(folder, suffixes):
    """The files of FOLDER (relative to the root) and its sub-folders but test/ ending in one of
    `suffixes`, in a fixed order; None when the folder does not exist."""
    base = os.path.join(ROOT, folder)
    if not os.path.isdir(base):
        return None
    found = []
    for dirpath, dirnames, filenames in os.walk(base):
        dirnames[:] = sorted(d for d in dirnames if d != "test")
        found += [os.path.join(dirpath, fn) for fn in sorted(filenames) if fn.endswith(suffixes)]
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folders", nargs="*", default=CHECKED)
    ap.add_argument("--strict", action="store_true", help="exit 1 when anything is over its limit")
    ap.add_argument("--top", type=int, default=3, help="how many of the largest to print per kind (default 3)")
    a = ap.parse_args()
    over = 0
    for folder in a.folders:
        paths = sources(folder, (".cpp", ".hpp"))
        if paths is None:
            print(f"size_limits: no folder {folder}", file=sys.stderr)
            return 2
        files, functions, classes = [], [], []
        for p in paths:
            rel = os.path.relpath(p, ROOT)
            with open(p, encoding="utf-8", errors="replace") as f:
                files.append((rel, sum(1 for _ in f)))
            fs, cs = scan(p)
            functions += [(f"{rel}:{start} {name}", n) for name, n, start in fs]
            classes += [(f"{rel}:{start} {name}", n) for name, n, start in cs]
        print(f"{folder}/ ({len(files)} files, {len(functions)} functions, {len(classes)} classes)")
        for what, items, limit, unit in (("file", files, FILE_LINES, "lines"),
                                         ("function", functions, FUNCTION_LINES, "lines"),
                                         ("class", classes, CLASS_MEMBERS, "members")):
            items = sorted(items, key=lambda x: (-x[1], x[0]))
            n_over = sum(1 for _, n in items if n > limit)
            over += n_over
            print(f"  largest {what}{'es' if what == 'class' else 's'} (limit {limit} {unit}; {n_over} over):")
            for label, n in items[:max(a.top, n_over)]:
                print(f"    {n:5d} {unit:7s} {label}{'  OVER' if n > limit else ''}")
    print(f"size_limits: {over} over the limits" + ("" if a.strict else " (report mode: exit 0)"))
    return 1 if a.strict and over else 0


if __name__ == "__main__":
    sys.exit(main())
