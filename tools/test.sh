#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite (ctest). Tests that need
# ../shared/data skip with a message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
# The tests build apart from ./build, with the project's SM_ASSERT checks on.
export SHEETMESH_BUILD_DIR=${SHEETMESH_BUILD_DIR:-build-tests}
export SHEETMESH_ASSERTS=${SHEETMESH_ASSERTS:-ON}
tools/setup.sh
build_dir=$SHEETMESH_BUILD_DIR
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" "$@"
