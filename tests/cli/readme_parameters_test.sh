#!/usr/bin/env bash
# docs/parameters.md is the parameter table's own (`sheetmesh-pipeline params --markdown`),
# between its two markers, and the front-end's defaults are the table's (`params --json`).
# Usage: readme_parameters_test.sh PIPELINE_BIN docs/parameters.md WEB_DEFAULTS_JSON
set -euo pipefail
pipeline=$1 readme=$2 web_defaults=$3
want=$("$pipeline" params --markdown)
have=$(sed -n '/^<!-- parameters: sheetmesh-pipeline params --markdown -->$/,/^<!-- end of parameters -->$/p' "$readme" | sed '1d;$d')
if [ "$want" != "$have" ]; then
  echo "$readme differs from the parameter table; refresh it with:" >&2
  echo "  tools/readme_parameters.sh" >&2
  diff <(echo "$want") <(echo "$have") >&2 || true
  exit 1
fi
if [ "$("$pipeline" params --json)" != "$(cat "$web_defaults")" ]; then
  echo "$web_defaults differs from the table's defaults; refresh it with:" >&2
  echo "  tools/readme_parameters.sh" >&2
  exit 1
fi
# The proto's comments say what each field means; its default is the table's alone.
proto=$(dirname "$readme")/../proto/sheetmesh/v1/parameters.proto
if grep -n "(default\|(defaults\|default [0-9a-z\"]" "$proto" >&2; then
  echo "$proto states a default (above); the table alone does: say what the field means" >&2
  exit 1
fi
echo "$readme lists the $(echo "$want" | tail -n +3 | wc -l) parameters of the table"
