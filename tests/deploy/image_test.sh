#!/usr/bin/env bash
# The image as CI uses it: base images from Debian's packages (tools/docker-base.sh), the
# Dockerfile built, the server started in it and the sample meshed from the host's CLI, a
# one-shot sheetmesh-pipeline container, a clean stop; then deploy/compose.yaml brought up
# (PostgreSQL, two servers, three workers, the gateway) and the sample meshed through a
# worker. Exits 77 (skipped) where Docker is not installed or dockerd cannot start.
#   tests/deploy/image_test.sh BUILD_DIR     (the host's sheetmesh and sheetmesh-pipeline)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:?BUILD_DIR}" && pwd)
cli=$build/client/sheetmesh
pipeline=$build/worker/pipeline/sheetmesh-pipeline
skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v docker >/dev/null || skip "docker is not installed (tools/setup.sh installs docker.io)"
tmp=$(mktemp -d /tmp/sheetmesh-image.XXXXXX)
chmod 755 "$tmp"
started_dockerd=
cleanup() {
  docker rm -f sheetmesh-image-test > /dev/null 2>&1 || true
  if [ -f "$tmp/deploy/compose.yaml" ]; then
    (cd "$tmp/deploy" && docker-compose -p sheetmeshtest down -v > /dev/null 2>&1) || true
  fi
  docker image prune -f > /dev/null 2>&1 || true  # the build stages left behind
  [ -z "$started_dockerd" ] || kill "$started_dockerd" 2> /dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
if ! docker info > /dev/null 2>&1; then
  [ "$(id -u)" = 0 ] || skip "dockerd is not running and this is not root"
  dockerd > "$tmp/dockerd.log" 2>&1 &
  started_dockerd=$!
  for _ in $(seq 60); do docker info > /dev/null 2>&1 && break; sleep 0.5; done
  docker info > /dev/null 2>&1 || skip "dockerd cannot start here: $(tail -3 "$tmp/dockerd.log")"
fi
[ -f "$root/web/dist/index.html" ] || fail "web/dist is missing: the build makes it (the gateway target)"

bash "$root/tools/docker-base.sh"
start=$(date +%s)
DOCKER_BUILDKIT=0 docker build --network host -t sheetmesh "$root" > "$tmp/build.log" 2>&1 ||
  { tail -40 "$tmp/build.log" >&2; fail "docker build"; }
echo "image built in $(( $(date +%s) - start )) s, $(docker image inspect sheetmesh --format '{{.Size}}' | awk '{printf "%.0f MB", $1 / 1e6}')"

# The embedded default, meshed from the host.
mkdir -p "$tmp/volumes" "$tmp/work" "$tmp/out"
chmod 777 "$tmp/work"
"$pipeline" phantom --preset=sample -o "$tmp/volumes/rock_128x112x96_u8.raw" > /dev/null
cp "$tmp/volumes/rock_128x112x96_u8.raw" "$tmp/work/"
docker run -d --name sheetmesh-image-test -p 127.0.0.1::50051 -v "$tmp/volumes:/volumes:ro" sheetmesh > /dev/null
port=$(docker port sheetmesh-image-test 50051 | head -1 | sed 's/.*://')
for _ in $(seq 120); do "$cli" health --server="127.0.0.1:$port" > /dev/null 2>&1 && break; sleep 0.5; done
[ "$("$cli" health --server="127.0.0.1:$port")" = SERVING ] || fail "the server in the container is not SERVING"
"$cli" mesh "$tmp/volumes/rock_128x112x96_u8.raw" --server="127.0.0.1:$port" --r=7 -o "$tmp/out" > "$tmp/mesh.log" ||
  { cat "$tmp/mesh.log" >&2; fail "mesh through the container"; }
grep -q '"similarity"' "$tmp/out/report.json" || fail "no report.json from the container"
# By path, under the container's /volumes.
"$cli" mesh /volumes/rock_128x112x96_u8.raw --reference --server="127.0.0.1:$port" --r=7 -o "$tmp/out-ref" > /dev/null ||
  fail "mesh by reference"
# One-shot, as a CI step.
docker run --rm -v "$tmp/work:/work" sheetmesh sheetmesh-pipeline run /work/rock_128x112x96_u8.raw --r=7 \
  -o /work/out > "$tmp/oneshot.log" 2>&1 || { cat "$tmp/oneshot.log" >&2; fail "one-shot sheetmesh-pipeline"; }
grep -q '"similarity"' "$tmp/work/out/report.json" || fail "the one-shot run wrote no report"
start=$(date +%s)
docker stop -t 30 sheetmesh-image-test > /dev/null
code=$(docker inspect sheetmesh-image-test --format '{{.State.ExitCode}}')
[ "$code" = 0 ] || fail "the server exited $code on docker stop"
echo "embedded default: SERVING, meshed by upload and by path, one-shot run, stopped cleanly in $(( $(date +%s) - start )) s"

# The compose file: PostgreSQL, two servers, three workers, the gateway.
command -v docker-compose > /dev/null || fail "docker-compose is not installed (tools/setup.sh installs it)"
mkdir -p "$tmp/deploy/volumes"
cp -r "$root/deploy/compose.yaml" "$root/deploy/postgres" "$tmp/deploy/"
head -c 24 /dev/urandom | base64 > "$tmp/deploy/worker_token"
chmod 644 "$tmp/deploy/worker_token"
cp "$tmp/volumes/rock_128x112x96_u8.raw" "$tmp/deploy/volumes/"
(cd "$tmp/deploy" && DOCKER_BUILDKIT=0 docker-compose -p sheetmeshtest up -d --build --scale worker=3 > "$tmp/compose.log" 2>&1) ||
  { cat "$tmp/compose.log" >&2; fail "docker-compose up"; }
for _ in $(seq 120); do "$cli" health --server=127.0.0.1:50052 > /dev/null 2>&1 && break; sleep 0.5; done
"$cli" mesh "$tmp/volumes/rock_128x112x96_u8.raw" --server=127.0.0.1:50052 --r=7 -o "$tmp/out-compose" > "$tmp/mesh2.log" ||
  { cat "$tmp/mesh2.log" >&2; (cd "$tmp/deploy" && docker-compose -p sheetmeshtest logs --tail=30) >&2; fail "mesh through compose"; }
grep -q '"similarity"' "$tmp/out-compose/report.json" || fail "no report through compose"
# The gateway may come up after the servers (on a busy machine it once answered too late).
listed=0
for _ in $(seq 60); do
  curl -sf http://127.0.0.1:8080/v1/jobs | grep -q '"SUCCEEDED"' && { listed=1; break; }
  sleep 0.5
done
[ "$listed" = 1 ] || fail "the gateway does not list the job (30 s)"
workers=$(cd "$tmp/deploy" && docker-compose -p sheetmeshtest ps -q worker | wc -l)
[ "$workers" = 3 ] || fail "$workers workers up, not 3"
echo "compose: PostgreSQL, two servers, $workers workers and the gateway; the sample meshed through server2 and a worker"
echo "image test passed"
