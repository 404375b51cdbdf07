#!/bin/bash
# Clean-build time of the pipeline and its tests at each commit given, one after the other
# (Release, 2 jobs, no ccache), each in a fresh worktree under /tmp:
#   bash bench/build_time.sh 26da2fe HEAD
# prints "COMMIT wall SECONDS cpu SECONDS" (cpu: the sum of ninja's step times).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
for commit in "$@"; do
  dir=$(mktemp -d /tmp/sheetmesh_build_time.XXXXXX)
  git -C "$root" worktree add --detach "$dir/src" "$commit" > /dev/null 2>&1
  mkdir "$dir/build"
  cmake -S "$dir/src" -B "$dir/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DSHEETMESH_BUILD_TESTS=ON > "$dir/configure.log" 2>&1
  start=$(date +%s.%N)
  CCACHE_DISABLE=1 cmake --build "$dir/build" -j2 --target sheetmesh-pipeline \
    sheetmesh_pipeline_tests > "$dir/build.log" 2>&1
  end=$(date +%s.%N)
  cpu=$(awk -F'\t' '!/^#/ { t += $2 - $1 } END { printf "%.1f", t / 1000 }' "$dir/build/.ninja_log")
  printf '%s wall %.1f cpu %s\n' "$commit" "$(echo "$end - $start" | bc)" "$cpu"
  git -C "$root" worktree remove --force "$dir/src"
  rm -rf "$dir"
done
