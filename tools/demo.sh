#!/usr/bin/env bash
# The main job on the embedded default: installs what is missing, builds, makes the bundled
# sample volume, starts sheetmesh-server on one data folder, meshes the sample through
# `sheetmesh mesh` (extraction, surface, similarity, volume mesh), stops the server and
# prints the folder with the meshes and the report.
# Usage: tools/demo.sh [OUT_DIR]   (default ./demo-out)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
build_dir=${SHEETMESH_BUILD_DIR:-build}
out=${1:-demo-out}
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin="$build_dir"

volume="$out/sample_128x112x96_u8.raw"
"$bin/worker/pipeline/sheetmesh-pipeline" phantom --preset=sample -o "$volume"

# One process, one data folder: the job store, the blobs and the workers' scratch.
rm -f "$out/server.port"
"$bin/server/sheetmesh-server" --data_dir="$out/server-data" --address=127.0.0.1:0 \
  --port_file="$out/server.port" > "$out/server.log" 2>&1 &
server_pid=$!
stop_server() {
  if kill -0 "$server_pid" 2>/dev/null; then
    kill -TERM "$server_pid"
    wait "$server_pid" || true
  fi
}
trap stop_server EXIT
for _ in $(seq 600); do
  [ -s "$out/server.port" ] && break
  kill -0 "$server_pid" 2>/dev/null || { cat "$out/server.log" >&2; exit 1; }
  sleep 0.05
done
[ -s "$out/server.port" ] || { echo "sheetmesh-server did not start; see $out/server.log" >&2; exit 1; }
server="127.0.0.1:$(cat "$out/server.port")"
echo "sheetmesh-server on $server, data in $out/server-data"

"$bin/client/sheetmesh" mesh "$volume" --server="$server" --extract --volume_mesh -o "$out/results"
stop_server
trap - EXIT
echo
/usr/bin/python3 - "$out/results/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s, m = r["similarity"], r["surface"]
print("surface: %d triangles, %d vertices; similarity %.4f (Dice %.4f, Hausdorff %.1f voxels)"
      % (m["triangles"], m["vertices"], s["similarity"], s["dice"], s.get("hausdorff_voxels", float("nan"))))
if "extraction" in r:
    print("extraction: %d pieces" % len(r.get("pieces", [])))
if "volume_mesh" in r:
    v = r["volume_mesh"]
    print("volume mesh: %s" % ", ".join("%s %s" % (k, v[k]) for k in ("nodes", "tetrahedra") if k in v))
PY
echo "results in $out/results"
