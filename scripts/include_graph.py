#!/usr/bin/env python3
"""The include graph of the project's own code, checked: no include cycle between components,
no include against the order of the rooms of flight_sw/ and verification/, no include of
plant/, render/ or verification/ from flight_sw/, and no include of bench/ from the shipped
programs (app/, flight_sw/).

  python3 scripts/include_graph.py [--root DIR]

A component is a header and its source of the same name in one folder (`verification/cosim/
cosim.hpp` and `cosim.cpp` are the component `verification/cosim/cosim`); it includes another
when either of its files names the other's header in `#include "..."`. A cycle (a component that
reaches itself through such includes: `a.cpp` including `b.hpp` while `b.cpp` includes `a.hpp`,
say) is what makes two files impossible to read, test or move one at a time. Tests (test/ folders)
and fuzz targets are leaves and are not counted.

The rooms (a folder's first level below flight_sw/ or verification/; files at flight_sw/'s root,
its configuration and text, are its base room "") may include only the rooms their order puts
below them (ROOMS; flight_sw/README.md and verification/README.md draw them): an include that
runs back up, or a room the order does not name, is forbidden. Exit 0 when the graph is clean,
1 with each cycle and each forbidden include printed.
"""
import argparse
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SOURCE_FOLDERS = ["include", "config", "sdk", "plant", "render", "flight_sw", "verification",
                  "identify", "distributed", "app", "bench"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
# Folders whose code ships in a program and so must not include benchmark code.
SHIPPED = ("app/", "flight_sw/")
# Folders the flight software never includes (it flies a real Tello without them).
NOT_FOR_FLIGHT = ("plant/", "render/", "verification/")


def _below(order):
    """{room: the rooms it may include} for a chain of rooms, each above the ones before it."""
    return {room: set(order[:i]) for i, room in enumerate(order)}


# Each house's rooms and what each may include besides itself.
ROOMS = {
    "flight_sw": _below(["", "perception", "navigation", "control", "guidance", "mission", "tello"]),
    # statistics <- scenario <- world <- cosim <- campaign <- report, search;  cosim <- frames;
    # plot <- report, search
    "verification": {
        **_below(["statistics", "scenario", "world", "cosim", "campaign"]),
        "plot": set(),
        "report": {"statistics", "plot", "scenario", "world", "cosim", "campaign"},
        "search": {"statistics", "plot", "scenario", "world", "cosim", "campaign"},
        "frames": {"statistics", "scenario", "world", "cosim"},
    },
}


def room_of(rel):
    """(house, room) of a path under flight_sw/ or verification/, else None."""
    parts = rel.split("/")
    if parts[0] not in ROOMS:
        return None
    return parts[0], (parts[1] if len(parts) > 2 else "")


def room_violation(rel, target):
    """Why `rel` may not include `target` (both paths from the root), or None."""
    if rel.startswith("flight_sw/") and target.startswith(NOT_FOR_FLIGHT):
        return f"{rel}: includes {target} (the flight software never includes {target.split('/')[0]}/)"
    here, there = room_of(rel), room_of(target)
    if not here or not there or here[0] != there[0]:
        return None
    house, room = here
    rooms = ROOMS[house]
    if room not in rooms:
        return f"{rel}: {house}/{room}/ is a room outside {house}'s documented order"
    if there[1] != room and there[1] not in rooms[room]:
        return f"{rel}: includes {target} ({house}'s room order puts {there[1] or 'its base'} above {room or 'its base'})"
    return None


def components(root):
    """{component: [file, ...]} for every .hpp/.cpp outside test/ folders, paths from root."""
    found = {}
    for top in SOURCE_FOLDERS:
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs[:] = [d for d in dirs if d != "test"]
            for name in files:
                stem, ext = os.path.splitext(name)
                if ext not in (".hpp", ".cpp"):
                    continue
                rel = os.path.relpath(os.path.join(folder, name), root)
                found.setdefault(os.path.splitext(rel)[0], []).append(rel)
    return found


def include_edges(root, comps):
    """{component: set of components it includes}, and the forbidden includes found."""
    edges, forbidden = {}, []
    for comp, files in comps.items():
        out = set()
        for rel in files:
            with open(os.path.join(root, rel), encoding="utf-8") as f:
                for target in INCLUDE.findall(f.read()):
                    # The include root is the source root ("plant/dynamics.hpp"); include/ holds
                    # the shared contracts as "shelfcross/....hpp".
                    for candidate in (target, os.path.join("include", target)):
                        stem = os.path.splitext(candidate)[0]
                        if stem in comps and stem != comp:
                            out.add(stem)
                    if rel.startswith(SHIPPED) and target.startswith("bench/"):
                        forbidden.append(f"{rel}: includes {target} (benchmark code in a shipped program)")
                    why = room_violation(rel, target)
                    if why:
                        forbidden.append(why)
        edges[comp] = out
    return edges, forbidden


def cycles(edges):
    """The strongly connected components with more than one member (Tarjan, iterative)."""
    index, low, on_stack, stack, result = {}, {}, set(), [], []
    counter = [0]
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, it = work[-1]
            advanced = False
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]
                    counter[0] += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(edges.get(nxt, ())))))
                    advanced = True
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                scc = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    scc.append(member)
                    if member == node:
                        break
                if len(scc) > 1:
                    result.append(sorted(scc))
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=ROOT, help="the source tree (default: this repository)")
    args = parser.parse_args(argv)
    comps = components(args.root)
    edges, forbidden = include_edges(args.root, comps)
    found = cycles(edges)
    for scc in found:
        print("include cycle: " + " <-> ".join(scc))
    for line in forbidden:
        print(line)
    print(f"include_graph: {len(comps)} components, {sum(len(e) for e in edges.values())} includes, "
          f"{len(found)} cycles, {len(forbidden)} forbidden includes")
    return 1 if found or forbidden else 0


if __name__ == "__main__":
    sys.exit(main())
