#!/usr/bin/env bash
# Builds sheetmesh-gateway from Debian's Go packages only (GOPATH mode, no module
# downloads): Go code and the OpenAPI document generated from proto/sheetmesh/v1 and
# deploy/gateway/sheetmesh_gateway.yaml, the front-end (web/, npm) embedded.
# Usage: tools/build_gateway.sh [BUILD_DIR]     (default ./build; writes BUILD_DIR/gateway/)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=$(realpath -m "${1:-build}")
out=$build/gateway
gopath=$out/gopath
src=$gopath/src/sheetmesh
mkdir -p "$src/v1" "$src/gateway"

# The front-end, unless it is already built from these sources.
web_stamp=$out/web.stamp
web_sum=$(cd web && find . -path ./node_modules -prune -o -path ./dist -prune -o -type f -print0 |
  sort -z | xargs -0 sha256sum | sha256sum | cut -c1-64)
# SHEETMESH_WEB_PREBUILT=1 takes web/dist as it is (an image build without Node).
if [ "${SHEETMESH_WEB_PREBUILT:-0}" = 1 ] && [ -f web/dist/index.html ]; then
  :
elif [ ! -f web/dist/index.html ] || [ "$(cat "$web_stamp" 2>/dev/null)" != "$web_sum" ]; then
  (cd web && { [ -d node_modules ] && [ node_modules -nt package-lock.json ] || npm ci --no-audit --no-fund --loglevel=error; } &&
    npm run --silent build)
  echo "$web_sum" > "$web_stamp"
fi

ts=Mgoogle/protobuf/timestamp.proto=github.com/golang/protobuf/ptypes/timestamp
yaml=grpc_api_configuration=deploy/gateway/sheetmesh_gateway.yaml
protoc -I proto -I /usr/include \
  --go_out=plugins=grpc,$ts:"$gopath/src" \
  --grpc-gateway_out=logtostderr=true,$yaml,$ts:"$gopath/src" \
  --swagger_out=logtostderr=true,allow_merge=true,merge_file_name=sheetmesh,$yaml:"$src/gateway" \
  proto/sheetmesh/v1/{common,blobs,jobs,parameters,volumes}.proto  # workers.proto is internal
for f in gateway/*.go gateway/openapi_extra.json; do
  cp -p "$f" "$src/gateway/"
done
rm -rf "$src/gateway/webdist"
cp -r web/dist "$src/gateway/webdist"

export GO111MODULE=off GOPATH="$gopath:/usr/share/gocode" GOCACHE="$out/gocache" GOFLAGS=
# The version is the project's (CMakeLists.txt's project line), as the C++ programs have it.
version=$(sed -n 's/^project(sheetmesh VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
(cd "$src/gateway" && go vet . &&
  go build -trimpath -ldflags "-X main.version=${version:-unknown}" -o "$out/sheetmesh-gateway" .)
if [ "${SHEETMESH_GATEWAY_TEST:-0}" = 1 ]; then
  (cd "$src/gateway" && go test -count=1 .)
fi
echo "built $out/sheetmesh-gateway"
