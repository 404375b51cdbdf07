# sheetmesh on Debian 12: sheetmesh-server, sheetmesh-worker, sheetmesh-gateway (with the
# front-end) and both command lines, as a non-root user.
#   tools/docker-base.sh      # base images from Debian's packages where no registry is reachable
#   (cd web && npm ci && npm run build)   # the front-end, built outside (Debian 12's Node is too old for it)
#   DOCKER_BUILDKIT=0 docker build --network host -t sheetmesh .
# The embedded default:   docker run -p 50051:50051 -v sheetmesh-data:/data sheetmesh
# One-shot, as a CI step: docker run --rm -v "$PWD":/work sheetmesh sheetmesh-pipeline run /work/rock.tif -o /work/out
#
# Build stage: only what ships (no tests, benchmarks or fuzzers).
FROM debian:bookworm AS build
RUN apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      cmake ninja-build g++ pkg-config ca-certificates \
      libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev libabsl-dev libtiff-dev \
      zlib1g-dev nlohmann-json3-dev libnanoflann-dev libeigen3-dev libpng-dev \
      libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libsqlite3-dev \
      libssl-dev libpq-dev libjpeg-dev libhdf5-dev libgdcm-dev libexodusii-dev \
      golang-go golang-grpc-gateway golang-github-grpc-ecosystem-grpc-gateway-dev \
      golang-goprotobuf-dev golang-google-grpc-dev golang-google-genproto-dev > /dev/null
WORKDIR /src
COPY . .
RUN test -f web/dist/index.html || { echo "build the front-end first: (cd web && npm ci && npm run build)"; exit 1; } \
    && cmake -S . -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release -DSHEETMESH_BUILD_TESTS=OFF \
         -DSHEETMESH_BUILD_BENCHMARKS=OFF -DSHEETMESH_BUILD_FUZZERS=OFF > /dev/null \
    && cmake --build /build -j"$(nproc)" --target sheetmesh-server sheetmesh-worker sheetmesh \
         sheetmesh-pipeline sheetmesh_python_stubs \
    && SHEETMESH_WEB_PREBUILT=1 bash tools/build_gateway.sh /build \
    && strip /build/server/sheetmesh-server /build/worker/remote/sheetmesh-worker \
         /build/client/sheetmesh /build/worker/pipeline/sheetmesh-pipeline

# Run stage: the shared libraries the binaries link, TetGen for volume meshes, Python with
# gRPC for the lab-side client.
FROM debian:bookworm-slim
RUN apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      libopenvdb10.0 libtbb12 libabsl20220623 libtiff6 libpng16-16 libgrpc++1.51 libgrpc29 \
      libprotobuf32 libsqlite3-0 libssl3 libpq5 libblosc1 libboost-iostreams1.74.0 zlib1g tetgen \
      libjpeg62-turbo libgdcm3.0 libhdf5-103-1 libexodusii5 libnetcdf19 \
      python3 python3-grpcio python3-protobuf > /dev/null \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --uid 10001 --home-dir /data sheetmesh \
    && mkdir -p /data /volumes && chown sheetmesh /data
COPY --from=build /build/server/sheetmesh-server /build/worker/remote/sheetmesh-worker \
     /build/client/sheetmesh /build/worker/pipeline/sheetmesh-pipeline \
     /build/gateway/sheetmesh-gateway /usr/local/bin/
COPY --from=build /build/python /opt/sheetmesh/python
COPY --from=build /src/client/python /opt/sheetmesh/client
ENV SHEETMESH_PYTHON_STUBS=/opt/sheetmesh/python
USER sheetmesh
WORKDIR /data
VOLUME /data
EXPOSE 50051 8080
# Volumes named by path must lie under /volumes (mount the lab's storage there). Any other
# command runs instead (sheetmesh-pipeline, sheetmesh-worker, sheetmesh-gateway, sheetmesh).
CMD ["sheetmesh-server", "--address=0.0.0.0:50051", "--data_dir=/data", "--allowed_root=/volumes"]
