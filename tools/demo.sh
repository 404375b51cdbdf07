#!/usr/bin/env bash
# The main job on the bundled sample: installs what is missing, builds, generates the sample
# phantom and runs the pipeline on it, leaving the results in a folder it prints.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
build_dir=${SHEETMESH_BUILD_DIR:-build}
out=${1:-demo-out}
mkdir -p "$out"
"$build_dir/worker/pipeline/sheetmesh-pipeline" phantom --preset=sample -o "$out/sample_128x112x96_u8.raw"
"$build_dir/worker/pipeline/sheetmesh-pipeline" info "$out/sample_128x112x96_u8.raw" --json > "$out/info.json"
"$build_dir/worker/pipeline/sheetmesh-pipeline" info "$out/sample_128x112x96_u8.raw"
echo "results in $(cd "$out" && pwd)"
