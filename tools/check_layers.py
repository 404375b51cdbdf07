#!/usr/bin/python3
"""Checks every include of the layered folders against their rules, and fails naming each
include that points where its layer may not.

    /usr/bin/python3 tools/check_layers.py LAYERS_TXT SOURCE_DIR

LAYERS_TXT (written by CMake from its sheetmesh_layer_rule calls) has one rule per line,
"FOLDER=ALLOWED,ALLOWED,...": the files whose path starts with FOLDER may include files
under their own folder, common/, and the ALLOWED folders. A file belongs to the longest
FOLDER its path starts with; so does an included path. Includes under no FOLDER (the
standard library, third-party headers) are not checked.

It also fails on a cycle of modules (a module is a header with its source: x.h and x.cc):
two modules that need each other are one module, or want a small shared header.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def cycles(needs):
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(needs.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(100000)
    for v in sorted(needs):
        if v not in index:
            visit(v)
    return out


def main():
    rules_file, root = sys.argv[1], sys.argv[2]
    rules = {}
    for line in open(rules_file):
        line = line.strip()
        if not line:
            continue
        folder, _, allowed = line.partition("=")
        rules[folder] = {a for a in allowed.split(",") if a} | {"common", folder}
    rules.setdefault("sheetmesh", set())  # the generated protos
    keys = sorted(rules, key=len, reverse=True)

    def layer_of(path):
        for k in keys:
            if path == k or path.startswith(k if k.endswith("/") else k + "/") or \
                    (os.path.basename(k) and path.startswith(k) and "/" not in path[len(k):]):
                return k
        return None

    wrong = []
    checked = 0
    needs = {}  # module -> the modules it includes
    for top in ("common", "worker", "server", "client"):
        for dirpath, _, names in os.walk(os.path.join(root, top)):
            for name in names:
                if not name.endswith((".h", ".cc")):
                    continue
                path = os.path.relpath(os.path.join(dirpath, name), root)
                own = layer_of(path)
                if own is None:
                    continue
                checked += 1
                module = path.rsplit(".", 1)[0]
                for n, text in enumerate(open(os.path.join(root, path), encoding="utf-8"), 1):
                    m = INCLUDE.match(text)
                    if not m:
                        continue
                    other = m.group(1).rsplit(".", 1)[0]
                    if other != module and os.path.exists(os.path.join(root, m.group(1))):
                        needs.setdefault(module, set()).add(other)
                    target = layer_of(m.group(1))
                    if target is not None and target not in rules[own]:
                        wrong.append("%s:%d: %s (layer %s) includes %s (layer %s), which it may not; "
                                     "its layer may include %s" % (
                                         path, n, path, own, m.group(1), target,
                                         ", ".join(sorted(rules[own] - {own}))))
    for cycle in cycles(needs):
        wrong.append("modules that include each other: %s (break the cycle: one module, or a "
                     "small header both include)" % " <-> ".join(cycle))
    for w in wrong:
        print(w, file=sys.stderr)
    if wrong:
        print("%d includes point where their layer may not, or close a cycle (rules: the "
              "sheetmesh_layer_rule calls of the CMakeLists.txt files)" % len(wrong),
              file=sys.stderr)
        return 1
    print("layers: %d files, every include within its rules, no module cycle" % checked)
    return 0


if __name__ == "__main__":
    sys.exit(main())
