#!/usr/bin/env bash
# Every shipped program answers --version with the project's version and exits 0.
# Usage: version_test.sh VERSION PROGRAM...
set -uo pipefail
want=$1
shift
status=0
for program in "$@"; do
  name=$(basename "$program")
  out=$("$program" --version 2>&1)
  rc=$?
  if [ "$rc" != 0 ] || [ "$out" != "$name $want" ]; then
    echo "FAIL $name --version: exit $rc, said '$out', wanted '$name $want'"
    status=1
  else
    echo "ok   $out"
  fi
done
exit $status
