#!/usr/bin/env bash
# Writes the parameter table (`sheetmesh-pipeline params --markdown`) into docs/parameters.md
# between its markers, and its defaults (`params --json`) into
# web/src/parameter_defaults.json, where the front-end's form takes them from.
# Usage: tools/readme_parameters.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
table=$("$build/worker/pipeline/sheetmesh-pipeline" params --markdown)
"$build/worker/pipeline/sheetmesh-pipeline" params --json > web/src/parameter_defaults.json
/usr/bin/python3 - "$table" <<'PY'
import re, sys
table = sys.argv[1]
text = open("docs/parameters.md").read()
begin = "<!-- parameters: sheetmesh-pipeline params --markdown -->\n"
end = "<!-- end of parameters -->"
i, j = text.index(begin) + len(begin), text.index(end)
open("docs/parameters.md", "w").write(text[:i] + table + "\n" + text[j:])
PY
