#!/usr/bin/env bash
# Times `sheetmesh-pipeline info` on a paper-scale phantom (1012 x 1024 x 931 uint8) against
# `cat FILE > /dev/null` in the same run, and reports peak RSS. Usage:
#   bench/info_scale.sh [BUILD_DIR] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
runs=${2:-5}
cli="$build/worker/pipeline/sheetmesh-pipeline"
data=bench/data
file=$data/paper_1012x1024x931_u8.raw
mkdir -p "$data"
if [ ! -f "$file" ]; then
  "$cli" phantom --preset=paper -o "$file"
fi
size=$(stat -c %s "$file")
median() { sort -n | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
cat_times=() info_times=() rss=()
for i in $(seq "$runs"); do
  cat_times+=("$( { /usr/bin/time -f %e cat "$file" > /dev/null; } 2>&1 )")
  out=$( { /usr/bin/time -f "%e %M" "$cli" info "$file" > /dev/null; } 2>&1 )
  info_times+=("${out% *}")
  rss+=("${out#* }")
done
cat_med=$(printf '%s\n' "${cat_times[@]}" | median)
info_med=$(printf '%s\n' "${info_times[@]}" | median)
rss_max=$(printf '%s\n' "${rss[@]}" | sort -n | tail -1)
"$cli" info "$file" | sed -n -E '/^(sheet|thickness|components|time)/p'
echo "file bytes:        $size"
echo "cat (median of $runs):   ${cat_med} s   [${cat_times[*]}]"
echo "info (median of $runs):  ${info_med} s   [${info_times[*]}]"
echo "info / cat:        $(awk -v a="$info_med" -v b="$cat_med" 'BEGIN {printf "%.1f", a / b}')x"
echo "peak RSS:          $((rss_max / 1024)) MiB = $(awk -v r="$rss_max" -v s="$size" 'BEGIN {printf "%.1f", 100 * r * 1024 / s}')% of the file"
