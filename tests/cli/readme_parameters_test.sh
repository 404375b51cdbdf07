#!/usr/bin/env bash
# README's parameter list is the parameter table's own (`sheetmesh-pipeline params
# --markdown`), between its two markers.
# Usage: readme_parameters_test.sh PIPELINE_BIN README
set -euo pipefail
pipeline=$1 readme=$2
want=$("$pipeline" params --markdown)
have=$(sed -n '/^<!-- parameters: sheetmesh-pipeline params --markdown -->$/,/^<!-- end of parameters -->$/p' "$readme" | sed '1d;$d')
if [ "$want" != "$have" ]; then
  echo "README's parameter list differs from the table; refresh it with:" >&2
  echo "  tools/readme_parameters.sh" >&2
  diff <(echo "$want") <(echo "$have") >&2 || true
  exit 1
fi
echo "README lists the $(echo "$want" | tail -n +3 | wc -l) parameters of the table"
