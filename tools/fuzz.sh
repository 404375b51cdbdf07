#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in ./build-fuzz and runs each for a
# bounded time on a copy of the checked-in corpus. Exits non-zero if any fuzzer finds a crash.
# Usage: tools/fuzz.sh [SECONDS_PER_TARGET]   (default 60)
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
cmake --build build-fuzz -j "$(nproc)" --target nrrd_header_fuzzer volume_file_fuzzer text_parsers_fuzzer
status=0
for target in nrrd_header volume_file text_parsers; do
  work=build-fuzz/corpus-$target
  mkdir -p "$work"
  cp -n tests/fuzz/corpus/$target/* "$work/" 2>/dev/null || true
  echo "== $target: ${seconds}s"
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1 \
      build-fuzz/tests/fuzz/${target}_fuzzer "$work" -max_total_time="$seconds" \
      -rss_limit_mb=2048 -timeout=10 -artifact_prefix=build-fuzz/crash-$target- 2>&1 |
      grep -E "^#[0-9]+ +DONE|ERROR|SUMMARY|Done"; then
    :
  fi
  if ls build-fuzz/crash-$target-* >/dev/null 2>&1; then
    echo "!! $target found crashing inputs: $(ls build-fuzz/crash-$target-*)"
    status=1
  fi
done
exit $status
