#!/usr/bin/env python3
"""The import graph of src/ by folder, and the check that every folder imports only the folders
below it in the layer order. Prints the graph as a Markdown table, the one in docs/architecture.md (or a Graphviz
dot text with the number of use statements on each edge, with --dot); with --check exits 1 naming each import that goes upward or sideways.

With --doc FILE the table is also compared with the one FILE holds between the lines
`<!-- import-graph -->` and `<!-- /import-graph -->` (a difference fails --check), and
--update writes it there.

usage: scripts/import-graph.py [--check] [--dot] [--doc FILE [--update]] [SRC]
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
    update = "--update" in argv
    doc = argv[argv.index("--doc") + 1] if "--doc" in argv else None
    rest = [a for i, a in enumerate(argv) if not a.startswith("--") and (i == 0 or argv[i - 1] != "--doc")]
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
    order = {name: i for i, name in enumerate(LAYERS)}
    table = ["| folder | uses modules of |", "|---|---|"]
    for layer in reversed(LAYERS):
        out = sorted({b for (a, b) in edges if a == layer}, key=lambda b: order.get(b, 99))
        table.append(f"| {layer} | {', '.join(out) if out else '-'} |")
    if not dot:
        print("\n".join(table))
    if doc:
        text = open(doc, encoding="utf-8").read()
        start, end = "<!-- import-graph -->\n", "<!-- /import-graph -->"
        i, j = text.find(start), text.find(end)
        if i < 0 or j < i:
            print(f"{doc}: no {start.strip()} ... {end} block", file=sys.stderr)
            return 1
        block = "\n".join(table) + "\n"
        if update:
            with open(doc, "w", encoding="utf-8") as f:
                f.write(text[:i + len(start)] + block + text[j:])
        elif text[i + len(start):j] != block:
            bad.append(f"the table in {doc} is not the graph of the sources: "
                       f"run scripts/import-graph.py --doc {doc} --update")
    if check and bad:
        for line in bad:
            print("import against the layers: " + line, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
