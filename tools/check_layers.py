#!/usr/bin/python3
"""Checks every include of the layered folders against their rules, and fails naming each
include that points where its layer may not.

    /usr/bin/python3 tools/check_layers.py LAYERS_TXT SOURCE_DIR

LAYERS_TXT (written by CMake from its sheetmesh_layer_rule calls) has one rule per line,
"FOLDER=ALLOWED,ALLOWED,...": the files whose path starts with FOLDER may include files
under their own folder, common/, and the ALLOWED folders. A file belongs to the longest
FOLDER its path starts with; so does an included path. Includes under no FOLDER (the
standard library, third-party headers) are not checked.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


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
                for n, text in enumerate(open(os.path.join(root, path), encoding="utf-8"), 1):
                    m = INCLUDE.match(text)
                    if not m:
                        continue
                    target = layer_of(m.group(1))
                    if target is not None and target not in rules[own]:
                        wrong.append("%s:%d: %s (layer %s) includes %s (layer %s), which it may not; "
                                     "its layer may include %s" % (
                                         path, n, path, own, m.group(1), target,
                                         ", ".join(sorted(rules[own] - {own}))))
    for w in wrong:
        print(w, file=sys.stderr)
    if wrong:
        print("%d includes point where their layer may not (rules: the sheetmesh_layer_rule calls "
              "of the CMakeLists.txt files)" % len(wrong), file=sys.stderr)
        return 1
    print("layers: %d files, every include within its rules" % checked)
    return 0


if __name__ == "__main__":
    sys.exit(main())
