#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in ./build-fuzz and runs each for a
# bounded time on a copy of the checked-in corpus, two at a time, under a memory limit (the
# readers' budget is 64 MiB; libFuzzer stops at 2 GiB of RSS or a single 1 GiB allocation).
# Exits non-zero if any fuzzer finds a crash; each finding is kept in build-fuzz/crash-*, to
# be added to tests/fuzz/corpus/<target>/ once fixed (the replay test runs the corpus).
# Usage: tools/fuzz.sh [SECONDS_PER_TARGET [TARGET...]]   (default 60, every target)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
tools/setup.sh >/dev/null  # the packages (clang, libfuzzer) and a normal build
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -g -O1"
if [ ! -f build-fuzz/build.ninja ]; then
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_C_FLAGS="$flags" \
    -DSHEETMESH_BUILD_FUZZERS=ON -DSHEETMESH_BUILD_SERVICE=OFF -DSHEETMESH_BUILD_TESTS=OFF \
    -DSHEETMESH_BUILD_BENCHMARKS=OFF >/dev/null
fi
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(tiff_file nrrd_file vdb_file raw_file nrrd_header text_parsers)
cmake --build build-fuzz -j "$(nproc)" --target "${targets[@]/%/_fuzzer}"
run() {
  local target=$1 work=build-fuzz/corpus-$1 leaks=1
  mkdir -p "$work"
  cp -n tests/fuzz/corpus/$target/* "$work/" 2>/dev/null || true
  # OpenVDB 10 leaks the nodes it had read when a damaged file makes its topology reader
  # throw (tests/fuzz/corpus/vdb_file/openvdb_topology_leak); a job's child process frees
  # them when it ends. Leak checks stay on for the readers written here.
  [ "$target" != vdb_file ] || leaks=0
  ASAN_OPTIONS=detect_leaks=$leaks UBSAN_OPTIONS=halt_on_error=1 \
    build-fuzz/tests/fuzz/${target}_fuzzer "$work" -max_total_time="$seconds" \
    -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10 \
    -artifact_prefix=build-fuzz/crash-$target- > build-fuzz/$target.log 2>&1 || true
  echo "== $target: ${seconds}s: $(grep -E '^Done [0-9]+ runs' build-fuzz/$target.log | tail -1)"
  grep -E "ERROR|SUMMARY" build-fuzz/$target.log | head -5 || true
}
status=0
for ((i = 0; i < ${#targets[@]}; i += 2)); do
  run "${targets[i]}" &
  if ((i + 1 < ${#targets[@]})); then run "${targets[i + 1]}" & fi
  wait
done
for target in "${targets[@]}"; do
  if ls build-fuzz/crash-$target-* >/dev/null 2>&1; then
    echo "!! $target found crashing inputs: $(ls build-fuzz/crash-$target-*)"
    status=1
  fi
done
exit $status
