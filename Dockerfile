# sheetmesh-server and the `sheetmesh` client on Debian 12, the embedded default: one
# process, one data folder (/data). Build:  docker build -t sheetmesh .
# Run:    docker run -p 50051:50051 -v sheetmesh-data:/data sheetmesh
#
# Build stage: the same set-up script as a developer machine, then the tests.
FROM debian:bookworm AS build
WORKDIR /src
COPY . .
RUN apt-get update -qq && apt-get install -y -qq --no-install-recommends ca-certificates \
    && bash tools/setup.sh \
    && ctest --test-dir build --output-on-failure -j"$(nproc)" \
    && strip build/server/sheetmesh-server build/client/sheetmesh build/worker/pipeline/sheetmesh-pipeline

# Run stage: the shared libraries the binaries link, TetGen for volume meshes, and
# Python with gRPC for the lab-side client.
FROM debian:bookworm-slim
RUN apt-get update -qq && apt-get install -y -qq --no-install-recommends \
      libopenvdb10.0 libtbb12 libabsl20220623 libtiff6 libgrpc++1.51 libgrpc29 libprotobuf32 \
      libsqlite3-0 libssl3 libblosc1 libboost-iostreams1.74.0 zlib1g tetgen \
      python3 python3-grpcio python3-protobuf \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --uid 10001 --home-dir /data sheetmesh \
    && mkdir -p /data /volumes && chown sheetmesh /data
COPY --from=build /src/build/server/sheetmesh-server /src/build/client/sheetmesh \
     /src/build/worker/pipeline/sheetmesh-pipeline /usr/local/bin/
COPY --from=build /src/build/python /opt/sheetmesh/python
COPY --from=build /src/client/python /opt/sheetmesh/client
ENV SHEETMESH_PYTHON_STUBS=/opt/sheetmesh/python
USER sheetmesh
VOLUME /data
EXPOSE 50051
# Volumes named by path must lie under /volumes (mount the lab's storage there).
ENTRYPOINT ["sheetmesh-server", "--address=0.0.0.0:50051", "--data_dir=/data", "--allowed_root=/volumes"]
