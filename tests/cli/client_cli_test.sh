#!/usr/bin/env bash
# End-to-end test of the `sheetmesh` client CLI against a real sheetmesh-server: mesh by
# upload and by reference, upload, jobs list/get/watch/cancel/delete, artifacts get,
# health, and clear errors with non-zero exits for bad input.
# Usage: client_cli_test.sh SERVER_BIN CLIENT_BIN PIPELINE_BIN
set -euo pipefail
server_bin=$1 cli=$2 pipeline=$3
tmp=$(mktemp -d)
server_pid=
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; [ -f "$tmp/server.log" ] && cat "$tmp/server.log" >&2; exit 1; }
# Runs a command and greps its whole output (no early-closed pipe under pipefail).
outputs() {
  local pattern=$1; shift
  local out
  out=$("$@") || return 1
  grep -qE -- "$pattern" <<< "$out"
}

mkdir -p "$tmp/root"
"$server_bin" --address=127.0.0.1:0 --data_dir="$tmp/data" --port_file="$tmp/port" \
  --allowed_root="$tmp/root" --workers=2 > "$tmp/server.log" 2>&1 &
server_pid=$!
for _ in $(seq 300); do [ -s "$tmp/port" ] && break; sleep 0.05; done
[ -s "$tmp/port" ] || fail "the server did not start"
s="--server=127.0.0.1:$(cat "$tmp/port")"

# Servers that cannot be reached: the error, then a one-line hint.
hint() {
  local pattern=$1; shift
  local out
  if out=$("$cli" health "$@" 2>&1); then fail "health $* succeeded"; fi
  grep -qE -- "$pattern" <<< "$out" || fail "health $*: no hint matching '$pattern' in: $out"
}
hint "^hint: nothing listens at 127.0.0.1:1:" --server=127.0.0.1:1
hint "^hint: --server takes HOST:PORT without a scheme \(--server=127.0.0.1:5\)" --server=http://127.0.0.1:5
hint "^hint: the host in --server=nohost.invalid:5 does not resolve" --server=nohost.invalid:5
hint "^hint: the server at 127.0.0.1:[0-9]+ does not speak TLS" "$s" --tls

outputs '^SERVING$' "$cli" health $s || fail health
# --help lists each program's own flags.
outputs '--data_dir' "$server_bin" --help || fail "sheetmesh-server --help lists no flags"
outputs '--server' "$cli" --help || fail "sheetmesh --help lists no flags"
"$pipeline" phantom --dims=64x64x64 --seed=2 -o "$tmp/root/rock_64x64x64_u8.raw" > /dev/null

# mesh by upload: plain progress lines (not a terminal), files downloaded.
"$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/out" --r=5 $s > "$tmp/mesh.txt" || fail "mesh: $(cat "$tmp/mesh.txt")"
# Stages stream in order; the first may end before the watch begins on a busy machine.
grep -q "^RUNNING stage [0-9]*/" "$tmp/mesh.txt" || fail "mesh printed no stages"
sed -n 's#^RUNNING stage \([0-9]*\)/.*#\1#p' "$tmp/mesh.txt" | sort -n -c 2> /dev/null ||
  fail "mesh printed its stages out of order: $(cat "$tmp/mesh.txt")"
grep -q "^SUCCEEDED" "$tmp/mesh.txt" || fail "mesh did not succeed"
for f in surface.ply surface.vtp surface.obj report.json; do [ -f "$tmp/out/$f" ] || fail "mesh wrote no $f"; done
# It ends with the job's figures from its report, as the offline CLI's summary has them.
want=$(/usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print('surface   %d triangles in %d piece%s, similarity %.4f' % (r['surface']['triangles'], len(r['pieces']), '' if len(r['pieces']) == 1 else 's', r['similarity']['similarity']))" "$tmp/out/report.json")
grep -qxF "$want" "$tmp/mesh.txt" || fail "mesh printed no '$want': $(cat "$tmp/mesh.txt")"
job=$(sed -n 's/^job \(jobs\/[^ ]*\).*/\1/p' "$tmp/mesh.txt")
[ -n "$job" ] || fail "mesh named no job"

# The same work again comes from the cache; --no_cache runs it.
outputs "identical work done before: $job" "$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/out2" --r=5 $s || fail cache
"$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/out3" --r=5 --no_cache $s > "$tmp/mesh3.txt"
grep -q "identical work" "$tmp/mesh3.txt" && fail "no_cache"
job3=$(sed -n 's/^job \(jobs\/[^ ]*\).*/\1/p' "$tmp/mesh3.txt")
cmp "$tmp/out/surface.ply" "$tmp/out3/surface.ply" || fail "the same job gave other bytes"

# A folder of slices and a detached NRRD upload as one volume each; a second upload of the
# folder with one slice changed sends that slice only.
"$pipeline" convert "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/slices" --out_format=tiff-folder > /dev/null
"$cli" mesh "$tmp/slices" -o "$tmp/folder" --r=5 $s > "$tmp/folder.txt" || fail "mesh of a folder: $(cat "$tmp/folder.txt")"
grep -q "volume of 64 files .*: sent 64 " "$tmp/folder.txt" || fail "folder upload: $(cat "$tmp/folder.txt")"
cmp -s <(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['similarity'])" "$tmp/folder/report.json") \
       <(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['similarity'])" "$tmp/out/report.json") \
  || fail "the folder of slices meshed differently from the raw file"
"$pipeline" phantom --dims=64x64x64 --seed=9 -o "$tmp/other_64x64x64_u8.raw" > /dev/null
"$pipeline" convert "$tmp/other_64x64x64_u8.raw" -o "$tmp/other" --out_format=tiff-folder > /dev/null
cp "$tmp/other/slice_00031.tif" "$tmp/slices/slice_00031.tif"
"$cli" mesh "$tmp/slices" -o "$tmp/folder2" --r=5 $s > "$tmp/folder2.txt" || fail "second folder mesh: $(cat "$tmp/folder2.txt")"
grep -q "sent 1 (.*), 63 stored already" "$tmp/folder2.txt" || fail "changed folder upload: $(cat "$tmp/folder2.txt")"
mkdir -p "$tmp/nhdr"
cp "$tmp/root/rock_64x64x64_u8.raw" "$tmp/nhdr/rock.raw"
printf 'NRRD0004\ntype: uint8\ndimension: 3\nsizes: 64 64 64\nencoding: raw\ndata file: rock.raw' > "$tmp/nhdr/rock.nhdr"
"$cli" mesh "$tmp/nhdr/rock.nhdr" -o "$tmp/nhdrout" --r=5 $s > "$tmp/nhdr.txt" || fail "mesh of a detached NRRD: $(cat "$tmp/nhdr.txt")"
grep -q "volume of 2 files" "$tmp/nhdr.txt" || fail "nhdr upload: $(cat "$tmp/nhdr.txt")"
[ -f "$tmp/nhdrout/report.json" ] || fail "detached NRRD mesh wrote no report"

# A volume mesh under its aim (tet.min_dihedral = 20, the most it takes) ends with the
# report's warning line, as the offline CLI prints it; one at or over it with none.
"$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/aim" --r=5 --volume_mesh --tet_min_dihedral=20 $s \
  > "$tmp/aim.txt" || fail "mesh --volume_mesh: $(cat "$tmp/aim.txt")"
worst=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['volume_mesh']['quality']['min_dihedral_degrees']['min'])" "$tmp/aim/report.json")
want=$(/usr/bin/python3 -c "import json,sys; v=json.load(open(sys.argv[1]))['volume_mesh']; q=v['quality']['min_dihedral_degrees']; print('volume    %d tetrahedra, min dihedral %.2f° (mean %.2f°)' % (v['tetrahedra'], q['min'], q['mean']))" "$tmp/aim/report.json")
grep -qxF "$want" "$tmp/aim.txt" || fail "mesh --volume_mesh printed no '$want': $(cat "$tmp/aim.txt")"
if /usr/bin/python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < 20 else 1)" "$worst"; then
  grep -q "^warning   min dihedral .* under tet.min_dihedral = 20° at voxel (" "$tmp/aim.txt" ||
    fail "a minimum of $worst under 20 printed no warning: $(cat "$tmp/aim.txt")"
else
  ! grep -q "^warning   min dihedral" "$tmp/aim.txt" || fail "a minimum of $worst warned: $(cat "$tmp/aim.txt")"
fi
# A surface under the grid floor (the report's similarity.floor_warning) is a warning line
# too, and there is none without it.
if /usr/bin/python3 -c "import json,sys; sys.exit(0 if 'floor_warning' in json.load(open(sys.argv[1]))['similarity'] else 1)" "$tmp/aim/report.json"; then
  grep -q "^warning   similarity .* is under the grid model's" "$tmp/aim.txt" ||
    fail "a surface under the grid floor printed no warning: $(cat "$tmp/aim.txt")"
else
  ! grep -q "^warning   similarity" "$tmp/aim.txt" || fail "a floor warning without one in the report"
fi

# mesh by reference.
"$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" --reference -o "$tmp/ref" $s > /dev/null || fail "mesh --reference"
[ -f "$tmp/ref/report.json" ] || fail "reference mesh wrote no report"

# upload, jobs, artifacts.
outputs '^[0-9a-f]{64}/262144$' "$cli" upload "$tmp/root/rock_64x64x64_u8.raw" $s || fail upload
outputs "$job  SUCCEEDED" "$cli" jobs list $s || fail "jobs list"
[ "$("$cli" jobs list --page_size=1 --all_pages $s | wc -l)" -ge 4 ] || fail "jobs list --all_pages"
"$cli" jobs get "$job" $s --json | /usr/bin/python3 -c "import json,sys; j=json.load(sys.stdin); sys.exit(0 if j['state']=='SUCCEEDED' and j['artifacts'] else 1)" || fail "jobs get --json"
outputs SUCCEEDED "$cli" jobs watch "$job" $s || fail "jobs watch"
"$cli" artifacts get "$job" -o "$tmp/art" --name report.json $s > /dev/null || fail "artifacts get"
[ -f "$tmp/art/report.json" ] && [ ! -f "$tmp/art/surface.ply" ] || fail "artifacts get --name"
outputs "deleted $job" "$cli" jobs delete "$job" $s || fail "jobs delete"

# Cancel a long job.
"$pipeline" phantom --dims=224x224x224 --seed=3 -o "$tmp/root/big_224x224x224_u8.raw" > /dev/null
"$cli" mesh "$tmp/root/big_224x224x224_u8.raw" --reference --extract -o "$tmp/big" $s > "$tmp/big.txt" 2>&1 &
mesh_pid=$!
for _ in $(seq 200); do grep -q "^job " "$tmp/big.txt" && break; sleep 0.05; done
big=$(sed -n 's/^job \(jobs\/[^ ]*\).*/\1/p' "$tmp/big.txt")
[ -n "$big" ] || fail "no job for the long mesh"
"$cli" jobs cancel "$big" $s > /dev/null || fail "jobs cancel"
if wait "$mesh_pid"; then fail "mesh of a cancelled job must exit non-zero"; fi
grep -q "CANCELLED" "$tmp/big.txt" || fail "the cancelled mesh did not say so: $(cat "$tmp/big.txt")"

# Bad input: clear messages, non-zero exits.
expect_error() {
  local code=$1 want=$2; shift 2
  local out rc=0
  out=$("$@" 2>&1) || rc=$?
  [ "$rc" = "$code" ] || fail "exit $rc (not $code) for: $* -> $out"
  grep -q -- "$want" <<< "$out" || fail "no '$want' in: $out"
}
expect_error 2 "parameters.r = -2.0 must be a number in (0, 4096]" "$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/x" --r=-2 $s
expect_error 1 "PERMISSION_DENIED" "$cli" mesh /etc/hostname --reference -o "$tmp/x" $s
expect_error 1 "NOT_FOUND" "$cli" jobs get jobs/nope $s
expect_error 1 "no file 'nope.ply'" "$cli" artifacts get "$job3" -o "$tmp/x" --name nope.ply $s
expect_error 1 "UNAVAILABLE" "$cli" health --server=127.0.0.1:1
expect_error 2 "junk.nrrd" bash -c "printf 'NRRD0004\ntype: complex\n\n' > '$tmp/junk.nrrd' && '$cli' mesh '$tmp/junk.nrrd' -o '$tmp/x' $s"
expect_error 2 "usage" "$cli" jobs get $s
# A failed volume stage: the job FAILED, and what its run kept is downloaded all the same.
expect_error 2 "kept as artifacts: surface.ply" "$cli" mesh "$tmp/root/rock_64x64x64_u8.raw" -o "$tmp/kept" \
  --r=5 --volume_mesh --max_tetrahedra=10 $s
for f in surface.ply report.json; do [ -f "$tmp/kept/$f" ] || fail "the failed job's kept $f was not downloaded"; done
[ ! -e "$tmp/kept/volume.vtu" ] || fail "a failed volume stage gave a volume.vtu"
echo "client CLI test passed"
