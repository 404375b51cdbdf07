#!/usr/bin/env bash
# End-to-end smoke test of the sheetmesh-pipeline command line on a small phantom: every
# command runs, writes what it says, and bad input exits non-zero with a clear message.
# Usage: cli_test.sh PATH_TO_sheetmesh-pipeline
set -euo pipefail
cli=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$cli" phantom --preset=sample -o "$tmp/s_128x112x96_u8.raw" | grep "sheet voxels" > /dev/null || fail phantom
[ -f "$tmp/s_128x112x96_u8.raw.truth.json" ] || fail "phantom truth"
# A raw name without dims: the phantom says how to read it back, and that works.
hint=$("$cli" phantom --preset=sample -o "$tmp/nameless.raw" | grep -o -- "--dims=[^ ]* --dtype=[a-z0-9]*") ||
  fail "phantom: no read-back hint for a raw name without dims"
"$cli" info "$tmp/nameless.raw" $hint > /dev/null || fail "phantom: its read-back hint"
"$cli" phantom --preset=sample -o "$tmp/s2_128x112x96_u8.raw" | grep "holds no dims" > /dev/null &&
  fail "phantom: a hint where the name has the dims"
"$cli" info "$tmp/s_128x112x96_u8.raw" --json > "$tmp/info.json"
/usr/bin/python3 -c "import json,sys; j=json.load(open('$tmp/info.json')); sys.exit(0 if j['dims']==[128,112,96] and j['sheet_voxels']>0 else 1)" || fail "info json"
"$cli" convert "$tmp/s_128x112x96_u8.raw" -o "$tmp/s.nrrd" --out_format=nrrd-gzip | grep wrote > /dev/null || fail convert
"$cli" surface "$tmp/s.nrrd" --r 7 -o "$tmp/surf" --similarity_hausdorff=false | grep "similarity" > /dev/null || fail surface
for f in surface.ply surface.vtp surface.vtu surface.obj report.json; do [ -f "$tmp/surf/$f" ] || fail "surface wrote no $f"; done
# meshio (which reads no PolyData) takes the surface .vtu with its thickness per triangle.
/usr/bin/python3 - "$tmp/surf/surface.vtu" <<'PY' || fail "meshio cannot read surface.vtu with its cell data"
import sys
import meshio
m = meshio.read(sys.argv[1])
tri = m.get_cells_type("triangle")
assert len(tri) > 0, "no triangles"
for name in ("thickness", "thickness_voxels", "piece"):
    assert name in m.cell_data and len(m.cell_data[name][0]) == len(tri), name
assert (m.cell_data["thickness_voxels"][0] >= 0).all()
PY
"$cli" score "$tmp/s.nrrd" "$tmp/surf/surface.ply" --similarity_hausdorff=false | grep "similarity" > /dev/null || fail score
cat > "$tmp/cfg.json" <<'JSON'
{"separate": {"D_ang": 140}, "r": 8, "volume_mesh": true}
JSON
"$cli" run "$tmp/s_128x112x96_u8.raw" --config "$tmp/cfg.json" --r 6 -o "$tmp/run" --similarity_hausdorff=false > "$tmp/run.txt" 2> "$tmp/run_progress.txt"
# Progress on stderr, a line per stage (piped), in order, ending with the write; stdout as before.
grep -q "^stage 1/[0-9]* read" "$tmp/run_progress.txt" || fail "run showed no progress: $(cat "$tmp/run_progress.txt")"
sed -n 's#^stage \([0-9]*\)/.*#\1#p' "$tmp/run_progress.txt" | sort -n -c || fail "run's stages out of order"
tail -1 "$tmp/run_progress.txt" | grep "write 100%" > /dev/null || fail "run's progress did not end with the write"
grep -q "^stage" "$tmp/run.txt" && fail "progress went to stdout"
grep -q "surface     r = 6" "$tmp/run.txt" || fail "the flag --r must override the config's r"
grep -q "volume mesh" "$tmp/run.txt" || fail "the config's volume_mesh must apply"
for f in model.vdb pieces.csv volume.vtu volume.msh volume.inp report.json; do [ -f "$tmp/run/$f" ] || fail "run wrote no $f"; done
"$cli" volume "$tmp/run/surface.ply" --volume "$tmp/s_128x112x96_u8.raw" -o "$tmp/vol" | grep "conform" > /dev/null || fail volume
[ -f "$tmp/vol/volume_report.json" ] || fail "volume report"
# Two processes (each with its own hash seed) give the same volume mesh, byte for byte.
"$cli" volume "$tmp/run/surface.ply" --volume "$tmp/s_128x112x96_u8.raw" -o "$tmp/vol2" \
  --output_volume_formats=vtu,msh > /dev/null || fail "volume again"
"$cli" volume "$tmp/run/surface.ply" --volume "$tmp/s_128x112x96_u8.raw" -o "$tmp/vol3" \
  --output_volume_formats=vtu,msh > /dev/null || fail "volume a third time"
cmp -s "$tmp/vol2/volume.vtu" "$tmp/vol3/volume.vtu" && cmp -s "$tmp/vol2/volume.msh" "$tmp/vol3/volume.msh" \
  || fail "the volume mesh differs between two runs"

# Bad input: a clear message naming the problem, exit code 2 (invalid argument).
expect_error() {
  local code=0
  out=$("$@" 2>&1) || code=$?
  [ "$code" -ne 0 ] || fail "expected an error from: $*"
  grep -q -- "$EXPECT" <<< "$out" || fail "message '$out' lacks '$EXPECT'"
}
head -c 1000 "$tmp/s_128x112x96_u8.raw" > "$tmp/cut_128x112x96_u8.raw"
EXPECT="truncated" expect_error "$cli" info "$tmp/cut_128x112x96_u8.raw"
EXPECT="matched no voxel" expect_error "$cli" info "$tmp/s_128x112x96_u8.raw" --labels=7
EXPECT="--r = -1.0 must be a number in (0, 4096]" expect_error "$cli" surface "$tmp/s_128x112x96_u8.raw" -o "$tmp/x" --r=-1
EXPECT="--r_sep is now --separate_r" expect_error "$cli" run "$tmp/s_128x112x96_u8.raw" -o "$tmp/x" --r_sep=6
EXPECT="--r (r) is not used by 'info'" expect_error "$cli" info "$tmp/s_128x112x96_u8.raw" --r=6
echo '{"surface": {"radius": 7}}' > "$tmp/bad.json"
EXPECT="unknown key 'surface.radius'" expect_error "$cli" run "$tmp/s_128x112x96_u8.raw" --config "$tmp/bad.json" -o "$tmp/x"
EXPECT="unknown command" expect_error "$cli" mesh-it
# A tetrahedron budget: met by `volume`, or refused naming the least possible.
"$cli" volume "$tmp/run/surface.ply" --volume "$tmp/s_128x112x96_u8.raw" -o "$tmp/vol_budget" \
  --output_volume_formats=vtu --max_tetrahedra=20000 > /dev/null || fail "volume with a budget"
/usr/bin/python3 -c "import json,sys; v=json.load(open(sys.argv[1]))['volume_mesh']
sys.exit(0 if v['tetrahedra'] <= 20000 and v['sizing']['max_tetrahedra'] == 20000 else 1)" \
  "$tmp/vol_budget/volume_report.json" || fail "the budget of 20000 tetrahedra was not kept"
EXPECT="max_tetrahedra = 10 is below the least this volume's sheets need" \
  expect_error "$cli" volume "$tmp/run/surface.ply" --volume "$tmp/s_128x112x96_u8.raw" -o "$tmp/x" \
  --max_tetrahedra=10
# --help lists the parameters and the commands' own flags, and exits 0.
"$cli" --help > "$tmp/help.txt" || fail "--help exited non-zero"
grep -q -- "--separate_r (separate.r)" "$tmp/help.txt" || fail "--help lists no parameters"
grep -q -- "--out_format" "$tmp/help.txt" || fail "--help lists no command flags"
# A volume path that is not UTF-8 is an error naming it, or a report with its name
# escaped; never an abort.
bad=$(printf '%s/s_\xff\xfe_128x112x96_u8.raw' "$tmp")
cp "$tmp/s_128x112x96_u8.raw" "$bad"
code=0; "$cli" surface "$bad" --r 9 -o "$tmp/nonutf8" --similarity_hausdorff=false > /dev/null 2>&1 || code=$?
[ "$code" -eq 0 ] || [ "$code" -eq 2 ] || fail "a non-UTF-8 path gave exit $code"
[ "$code" -ne 0 ] || /usr/bin/python3 -c "import json; json.load(open('$tmp/nonutf8/report.json'))" || fail "report.json of a non-UTF-8 path does not parse"
# A thick slab is a body: the surface says so, `score` on its PLY gives the report's
# similarity (prisms of the sheets and the bodies' insides), and `volume` makes it a region.
"$cli" phantom --preset=thick_slab --dims=48x48x52 -o "$tmp/slab_48x48x52_u8.raw" > /dev/null
"$cli" surface "$tmp/slab_48x48x52_u8.raw" --labels=255 --r=6 -o "$tmp/slab" --output_formats=ply \
  --similarity_hausdorff=false > "$tmp/slab.txt" || fail "surface of a thick slab"
grep -q "^pieces as   1 of 1 meshed as closed surfaces" "$tmp/slab.txt" || fail "the thick slab is not a body"
grep -qE "^            [0-9]+: body \(equivalent aperture [0-9.e+]+ voxels\), as a body it scores [0-9.]+, as a sheet [0-9.]+" "$tmp/slab.txt" ||
  fail "the slab's line does not say why it is a body: $(cat "$tmp/slab.txt")"
/usr/bin/python3 -c "import json,sys; p=json.load(open(sys.argv[1]))['representation']['pieces']; sys.exit(0 if all(x['reason'] for x in p) else 1)" \
  "$tmp/slab/report.json" || fail "a piece of the report without its reason"
"$cli" score "$tmp/slab_48x48x52_u8.raw" "$tmp/slab/surface.ply" --labels=255 --json \
  --similarity_hausdorff=false > "$tmp/slab_score.json" || fail "score of a surface with a body"
/usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); s=json.load(open(sys.argv[2]))
sys.exit(0 if abs(r['similarity']['similarity'] - s['similarity']) < 1e-9 else 1)" \
  "$tmp/slab/report.json" "$tmp/slab_score.json" || fail "score differs from the report with a body"
"$cli" volume "$tmp/slab/surface.ply" --volume "$tmp/slab_48x48x52_u8.raw" -o "$tmp/slab_vol" \
  --output_volume_formats=vtu > /dev/null || fail "volume of a surface with a body"
/usr/bin/python3 -c "import json,sys; v=json.load(open(sys.argv[1]))['volume_mesh']
sys.exit(0 if len(v['bodies']) == 1 and v['bodies'][0]['tetrahedra'] > 0 else 1)" \
  "$tmp/slab_vol/volume_report.json" || fail "the body is no region of the volume mesh"
echo "cli: all commands behaved"
