#!/usr/bin/env bash
# SCVD + triangles + similarity at r = 7 on the paper-scale phantom (1012 x 1024 x 931):
# wall time per stage and peak RSS. Usage: bench/surface_scale.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
cli="$build/worker/pipeline/sheetmesh-pipeline"
file=bench/data/paper_1012x1024x931_u8.raw
mkdir -p bench/data bench/out
[ -f "$file" ] || "$cli" phantom --preset=paper -o "$file"
/usr/bin/time -f "wall %e s, peak RSS %M KB" "$cli" surface "$file" --r 7 -o bench/out/paper_r7 --formats ply
