#!/usr/bin/env bash
# The main job on the embedded default: installs what is missing, builds, makes the bundled
# sample volume, starts sheetmesh-server on one data folder, meshes the sample through
# `sheetmesh mesh` (extraction, surface, similarity, volume mesh), reads the job's report
# back through sheetmesh-gateway (HTTP/JSON and the front-end, started beside the server),
# stops both and prints the folder with the meshes and the report.
# Usage: tools/demo.sh [--serve] [OUT_DIR]   (default ./demo-out; --serve keeps the server
# and the front-end running until Ctrl-C)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
build_dir=${SHEETMESH_BUILD_DIR:-build}
serve=0
if [ "${1:-}" = --serve ]; then
  serve=1
  shift
fi
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
gateway_pid=
stop_server() {
  for pid in $gateway_pid $server_pid; do
    if kill -0 "$pid" 2>/dev/null; then
      kill -TERM "$pid"
      wait "$pid" || true
    fi
  done
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

# The HTTP gateway and the front-end beside it.
gateway_bin="$bin/gateway/sheetmesh-gateway"
if [ -x "$gateway_bin" ]; then
  rm -f "$out/gateway.port"
  "$gateway_bin" --listen=127.0.0.1:${SHEETMESH_GATEWAY_PORT:-0} --server="$server" \
    --port_file="$out/gateway.port" > "$out/gateway.log" 2>&1 &
  gateway_pid=$!
  for _ in $(seq 600); do
    [ -s "$out/gateway.port" ] && break
    sleep 0.05
  done
  gateway="http://127.0.0.1:$(cat "$out/gateway.port")"
  echo "sheetmesh-gateway on $gateway (the front-end at $gateway/, OpenAPI at $gateway/openapi.json)"
fi

"$bin/client/sheetmesh" mesh "$volume" --server="$server" --extract --volume_mesh -o "$out/results"
if [ -n "$gateway_pid" ]; then
  # The same report over HTTP: the newest job's report.json, byte for byte.
  job=$(curl -sf "$gateway/v1/jobs?page_size=1" | /usr/bin/python3 -c 'import json,sys; print(json.load(sys.stdin)["jobs"][0]["name"])')
  curl -sf "$gateway/v1/$job/artifacts/report.json" -o "$out/report_over_http.json"
  cmp -s "$out/report_over_http.json" "$out/results/report.json" ||
    { echo "the report over HTTP differs from the one the CLI downloaded" >&2; exit 1; }
  echo "report.json over HTTP: $gateway/v1/$job/artifacts/report.json (same bytes)"
  if [ "$serve" = 1 ]; then
    echo "serving: open $gateway/#/$job (Ctrl-C stops)"
    wait "$gateway_pid" || true
  fi
fi
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
