#!/usr/bin/env python3
"""The import graph of src/ by folder, and the check that every folder imports only the folders
below it in the layer order. Prints the graph as a Markdown table (and a Graphviz dot text with
--dot); with --check exits 1 naming each import that goes upward or sideways.

usage: scripts/import-graph.py [--check] [--dot] [SRC]
"""
import collections
import os
import re
import sys

# The layers, lowest first: a folder may use modules of its own folder and of folders before it
LAYERS = ["util", "optimise", "model", "upf", "driver", "io", "fe", "fit", "analysis",
          "diagnose", "cli"]

MODULE = re.compile(r"^\s*module\s+(\w+)\s*(?:!.*)?$", re.M | re.I)
USE = re.compile(r"^\s*use\s*(?:,\s*(?:non_)?intrinsic\s*::)?\s*(\w+)", re.M | re.I)


def scan(src):
    """Folder of every module defined under src, and the modules each file uses."""
    where, uses = {}, {}
    for folder, _, files in sorted(os.walk(src)):
        for name in sorted(files):
            if not name.endswith((".f90", ".F90", ".inc")):
                continue
            path = os.path.join(folder, name)
            text = open(path, encoding="utf-8", errors="replace").read()
            layer = os.path.relpath(folder, src).split(os.sep)[0]
            for mod in MODULE.findall(text):
                where[mod.lower()] = layer
            uses[path] = (layer, {u.lower() for u in USE.findall(text)})
    return where, uses


def main(argv):
    check = "--check" in argv
    dot = "--dot" in argv
    rest = [a for a in argv if not a.startswith("--")]
    src = rest[0] if rest else os.path.join(os.path.dirname(__file__), "..", "src")
    where, uses = scan(src)
    edges = collections.Counter()
    bad = []
    for path, (layer, used) in sorted(uses.items()):
        for mod in sorted(used):
            target = where.get(mod)
            if target is None or target == layer:
                continue
            edges[(layer, target)] += 1
            if layer not in LAYERS or target not in LAYERS or \
                    LAYERS.index(target) > LAYERS.index(layer):
                bad.append(f"{os.path.relpath(path, src)} ({layer}) uses {mod} ({target})")
    if dot:
        print("digraph layers {\n  rankdir=BT;")
        for (a, b), n in sorted(edges.items()):
            print(f'  "{a}" -> "{b}" [label="{n}"];')
        print("}")
    else:
        print("| folder | imports (number of use statements) |")
        print("|---|---|")
        for layer in reversed(LAYERS):
            out = [f"{b} ({n})" for (a, b), n in sorted(edges.items(), key=lambda e: LAYERS.index(e[0][1]) if e[0][1] in LAYERS else 99) if a == layer]
            print(f"| {layer} | {', '.join(out) if out else '-'} |")
    if check and bad:
        for line in bad:
            print("import against the layers: " + line, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
