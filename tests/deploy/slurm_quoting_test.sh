#!/usr/bin/env bash
# deploy/slurm/submit_bricks.sh passes paths to the batch scripts as data: an output folder
# named out'$(touch PWNED)'x ran the command inside it (hardening, third round). A fake
# sbatch runs each --wrap script with sh, as Slurm does, and a fake pipeline records the
# arguments it got: nothing runs that the path names, and every path arrives whole.
# Usage: slurm_quoting_test.sh REPO_DIR
set -euo pipefail
repo=$(realpath "$1")
dir=$(mktemp -d /tmp/sheetmesh_slurm_quoting.XXXXXX)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
mkdir -p "$dir/bin" "$dir/work"
cat > "$dir/bin/sbatch" <<'SH'
#!/usr/bin/env bash
# Fake sbatch: runs the --wrap script with sh in the caller's folder; prints a job id.
for a in "$@"; do
  case $a in --wrap=*) printf '#!/bin/sh\n%s\n' "${a#--wrap=}" > "$FAKE_DIR/script.sh"; sh "$FAKE_DIR/script.sh" ;; esac
done
echo "$RANDOM"
SH
cat > "$dir/bin/fake-pipeline" <<'SH'
#!/usr/bin/env bash
# Fake sheetmesh-pipeline: a plan of two bricks; brick and merge record their arguments.
printf '%s\n' "$@" > "$FAKE_DIR/args.$1"
if [ "$1" = plan ]; then
  mkdir -p "$4"
  printf '{"bricks": [\n{"index": 0},\n{"index": 1}]}\n' > "$4/plan.json"
fi
SH
chmod +x "$dir/bin/sbatch" "$dir/bin/fake-pipeline"
cd "$dir/work"
out="out'\$(touch PWNED)'x \"two words\" \$HOME;\`touch PWNED2\`"
volume="vol 'quoted'.raw"
: > "$volume"
FAKE_DIR=$dir PATH="$dir/bin:$PATH" SHEETMESH_PIPELINE="$dir/bin/fake-pipeline" \
  bash "$repo/deploy/slurm/submit_bricks.sh" "$volume" "$out" --r=5 > "$dir/submitted"
[ ! -e PWNED ] && [ ! -e PWNED2 ] || fail "a path ran a command: $(ls)"
[ "$(sed -n 2p "$dir/args.brick")" = "$out.plan" ] || fail "brick got $(cat "$dir/args.brick")"
[ "$(sed -n 2p "$dir/args.merge")" = "$out.plan" ] || fail "merge got $(cat "$dir/args.merge")"
[ "$(sed -n 4p "$dir/args.merge")" = "$out" ] || fail "merge's output is $(sed -n 4p "$dir/args.merge")"
[ "$(sed -n 2p "$dir/args.plan")" = "$volume" ] || fail "plan got $(cat "$dir/args.plan")"
grep -q "2 tasks" "$dir/submitted" || fail "$(cat "$dir/submitted")"
echo "slurm submission: paths with quotes, \$(...), backquotes and spaces arrive whole and run nothing"
