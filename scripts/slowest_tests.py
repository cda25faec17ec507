#!/usr/bin/env python3
"""The slowest tests of a CTest run, from the JUnit file CTest writes (the test presets'
`outputJUnitFile`), so that a test growing slower shows at the end of every run.

  scripts/slowest_tests.py JUNIT_XML [--count N]

Prints the N (default 10) slowest tests with their wall time in seconds as CTest measured it,
then the sum over every test. Python 3 standard library only.
"""
import argparse
import sys
import xml.etree.ElementTree as ET


def slowest(path, count):
    """(seconds, name, status) of the `count` slowest test cases, and the sum over all."""
    cases = []
    for case in ET.parse(path).getroot().iter("testcase"):
        status = case.get("status", "run")
        if case.find("failure") is not None:
            status = "failed"
        cases.append((float(case.get("time", "0")), case.get("name", "?"), status))
    cases.sort(key=lambda c: (-c[0], c[1]))
    return cases[:count], sum(c[0] for c in cases), len(cases)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("junit", help="the JUnit XML file of a CTest run")
    parser.add_argument("--count", type=int, default=10)
    args = parser.parse_args()
    try:
        top, total, n = slowest(args.junit, args.count)
    except (OSError, ET.ParseError) as e:
        print(f"slowest_tests: {args.junit}: {e}")
        return 1
    print(f"slowest {len(top)} of {n} tests ({args.junit}; {total:.0f} s summed over all):")
    for seconds, name, status in top:
        print(f"  {seconds:8.1f} s  {name}" + ("" if status in ("run", "passed") else f"  ({status})"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
