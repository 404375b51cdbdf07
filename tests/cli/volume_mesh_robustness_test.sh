#!/usr/bin/env bash
# The volume-mesh reproductions of the robustness issue as regression cases: each run that
# was refused ("N pairs of sheet triangles intersect") or crashed TetGen (SIGSEGV, the
# recoversubfaces abort) now ends with a volume mesh whose every sheet triangle conforms,
# what was mended said in the report. Runs on ../shared/data's NETL and DPM volumes (skipped,
# saying so, where absent) and on the rough_network preset.
# Usage: volume_mesh_robustness_test.sh PATH_TO_sheetmesh-pipeline SHARED_DATA_DIR
set -euo pipefail
cli=$1
shared=${2:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cases=0

# mesh NAME COMMAND VOLUME FLAGS...: exit 0, a volume mesh, all sheet triangles conforming.
mesh() {
  local name=$1 cmd=$2 vol=$3
  shift 3
  local out="$tmp/$name" code=0 log
  log=$("$cli" "$cmd" "$vol" -o "$out" --volume_mesh --output_formats=ply \
    --output_volume_formats=vtu --similarity_hausdorff=false --similarity_grid_rates= "$@" 2>&1) ||
    code=$?
  cases=$((cases + 1))
  [ "$code" -eq 0 ] || fail "$name: exit $code: $(echo "$log" | tail -n 2)"
  /usr/bin/python3 - "$out/report.json" "$name" <<'PY' || fail "$name: the report"
import json, sys
vm = json.load(open(sys.argv[1]))["volume_mesh"]
c = vm["conformity"]
assert vm["tetrahedra"] > 0, "no tetrahedra"
assert c["conforming"] == c["sheet_triangles"] > 0, c
u = vm["untangled"]
print("  %-26s %7d tets, min dihedral %5.2f, untangled %s, removed %d, TetGen retries %d" % (
    sys.argv[2], vm["tetrahedra"], vm["quality"]["min_dihedral_degrees"]["min"],
    {k: v for k, v in u.items() if v}, vm["repaired_triangles"], len(vm["tetgen_recovery"])))
PY
}

"$cli" phantom --preset=rough_network -o "$tmp/rough_160x160x160_u8.raw" > /dev/null
mesh rough_surface_r5 surface "$tmp/rough_160x160x160_u8.raw" --r=5  # TetGen SIGSEGV before
mesh rough_surface_r4 surface "$tmp/rough_160x160x160_u8.raw" --r=4
mesh rough_run_r11 run "$tmp/rough_160x160x160_u8.raw" --r=11
# Refused at r = 2-3 before the last resorts (thin crossing splits, then removal of what
# stays crumpled, TetGen's own intersection check naming what it crashed on); the
# improvement is off in these: the failures were all before it.
mesh rough_surface_r3 surface "$tmp/rough_160x160x160_u8.raw" --r=3 --improve_passes=0
# The same surface read back from its PLY: TetGen crashed on every try (-Y: segfault;
# without: abort) on caps the mends left at junctions, now closed (closed_caps).
ply_log=$("$cli" volume "$tmp/rough_surface_r3/surface.ply" --volume "$tmp/rough_160x160x160_u8.raw" \
  -o "$tmp/rough_ply_r3" --output_volume_formats=vtu --improve_passes=0 2>&1) ||
  fail "rough_ply_r3: $(echo "$ply_log" | tail -n 2)"
cases=$((cases + 1))
/usr/bin/python3 - "$tmp/rough_ply_r3/volume_report.json" <<'PY' || fail "rough_ply_r3: the report"
import json, sys
vm = json.load(open(sys.argv[1]))["volume_mesh"]
c = vm["conformity"]
assert c["conforming"] == c["sheet_triangles"] > 0, c
assert vm["closed_caps"] > 0, vm["closed_caps"]
print("  %-26s %7d tets, min dihedral %5.2f, caps closed %d, TetGen retries %d" % (
    "rough_ply_r3", vm["tetrahedra"], vm["quality"]["min_dihedral_degrees"]["min"],
    vm["closed_caps"], len(vm["tetgen_recovery"])))
PY
"$cli" phantom --preset=sample -o "$tmp/sample_128x112x96_u8.raw" > /dev/null
mesh sample_surface_r2 surface "$tmp/sample_128x112x96_u8.raw" --labels=255 --r=2 --improve_passes=0
# Found by the property test: a sheet edge across the corner of a box face (TetGen crashed
# in unifysegments), a refinement round whose mesh did not fill the box.
"$cli" phantom --preset=grazing_sheet --seed=1964 --dims=64x64x64 -o "$tmp/graze_64x64x64_u8.raw" > /dev/null
mesh grazing_run_r8 run "$tmp/graze_64x64x64_u8.raw" --labels=255 --r=8
"$cli" phantom --preset=shallow_network --seed=5072 --dims=80x80x80 -o "$tmp/shallow_80x80x80_u8.raw" > /dev/null
mesh shallow_surface_r10 surface "$tmp/shallow_80x80x80_u8.raw" --labels=255 --r=10
if [ -n "$shared" ] && [ -f "$shared/netl_binary_fracture_small.tif" ]; then
  netl=$shared/netl_binary_fracture_small.tif
  dpm=$shared/dpm_3fractures_100x100x100_u8.raw
  mesh netl_surface_r5 surface "$netl" --labels=255 --r=5  # 4 pairs intersected before
  mesh netl_run_r5 run "$netl" --labels=255 --r=5
  mesh netl_surface_r2 surface "$netl" --labels=255 --r=2  # TetGen aborted (box facet)
  mesh netl_surface_r11 surface "$netl" --labels=255 --r=11
  mesh dpm_run_r3 run "$dpm" --dims=100x100x100 --labels=255 --r=3  # TetGen SIGSEGV under -Y
  mesh dpm_run_r4 run "$dpm" --dims=100x100x100 --labels=255 --r=4  # 2 pairs intersected
  mesh dpm_surface_r3 surface "$dpm" --dims=100x100x100 --labels=255 --r=3
  # Every TetGen run aborted on the box's seeds, lattices in sets on one sphere with the
  # sheet's trace at y = 49.5 (segment recovery); the seeds are now offset by 1e-4 voxel.
  mesh dpm_run_r7 run "$dpm" --dims=100x100x100 --labels=255 --r=7
  mesh dpm_surface_r2 surface "$dpm" --dims=100x100x100 --labels=255 --r=2 --improve_passes=0
else
  echo "../shared/data absent: the NETL and DPM reproductions are skipped"
fi
echo "volume mesh robustness: $cases runs meshed, every sheet triangle conforming"
