#!/usr/bin/env python3
"""Prints the link graph of Kaskad's own targets and fails on a cycle.

  usage: python3 scripts/target_graph.py [BUILD_DIR]     (default build/release, configured)

Runs `cmake --graphviz=BUILD_DIR/graph/kaskad.dot BUILD_DIR`, keeps the edges between our
targets (kaskad, kaskad_*; not kaskad_warnings, tests or system libraries) and prints them per
target with their scope, then a topological order (highest first) or the targets on a cycle.
The allowed edges themselves are checked by cmake/check_layers.cmake (CTest layer_check).
"""
import collections
import pathlib
import re
import subprocess
import sys

build = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "build/release")
dot = build / "graph" / "kaskad.dot"
dot.parent.mkdir(parents=True, exist_ok=True)
subprocess.run(["cmake", f"--graphviz={dot}", str(build)], check=True, stdout=subprocess.DEVNULL)

# CMake writes: "node1" -> "node2" [ style = dotted ] // from -> to   (none: PUBLIC or an
# executable's link, dashed: INTERFACE, dotted: PRIVATE)
edge = re.compile(r'-> "node\d+"\s*(?:\[ style = (\w+) \])?\s*// (\S+) -> (\S+)')
scope = {None: "public", "dashed": "interface", "dotted": "private"}


def ours(name):
    return (name == "kaskad" or name.startswith("kaskad_")) and name != "kaskad_warnings"


edges = collections.defaultdict(dict)
for m in edge.finditer(dot.read_text()):
    style, a, b = m.groups()
    if ours(a) and ours(b):
        edges[a][b] = scope[style]
nodes = set(edges) | {b for deps in edges.values() for b in deps}
for a in sorted(edges):
    print(f"{a} -> " + ", ".join(f"{b} ({s})" for b, s in sorted(edges[a].items())))

# Kahn's algorithm: what is left over lies on (or above) a cycle.
users = {n: 0 for n in nodes}
for deps in edges.values():
    for b in deps:
        users[b] += 1
ready = sorted(n for n in nodes if users[n] == 0)
order = []
while ready:
    n = ready.pop(0)
    order.append(n)
    for b in sorted(edges.get(n, {})):
        users[b] -= 1
        if users[b] == 0:
            ready.append(b)
count = sum(len(d) for d in edges.values())
if len(order) != len(nodes):
    print(f"{count} edges: CYCLE among " + " ".join(sorted(nodes - set(order))))
    sys.exit(1)
print(f"{count} edges, no cycle; highest first: " + " ".join(order))
