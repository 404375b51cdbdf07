#!/usr/bin/env bash
# Installs the Debian packages sheetmesh needs (only those missing), then configures and
# builds the project in Release into ./build ($SHEETMESH_BUILD_DIR chooses another folder,
# SHEETMESH_ASSERTS=ON turns the project's SM_ASSERT checks on). Safe to run again: quick
# when all is in place.
# Usage: tools/setup.sh            (as root on Debian 12, or with sudo available)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  # toolchain
  cmake ninja-build g++ ccache pkg-config time git
  # pipeline
  libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev libabsl-dev libtiff-dev
  zlib1g-dev nlohmann-json3-dev libnanoflann-dev libeigen3-dev tetgen
  # service
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libsqlite3-dev libssl-dev
  libpq-dev postgresql
  # tests, fuzzing, benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev clang libfuzzer-14-dev
  # Python tooling (always run with /usr/bin/python3)
  python3 python3-numpy python3-scipy python3-vtk9 python3-skimage python3-meshio
  python3-grpcio python3-protobuf python3-yaml python3-pygalmesh python3-matplotlib
  # the HTTP gateway (Go in GOPATH mode, no module downloads), previews, browser tests
  golang-go golang-grpc-gateway golang-github-grpc-ecosystem-grpc-gateway-dev
  golang-goprotobuf-dev golang-google-grpc-dev golang-google-genproto-dev libpng-dev chromium
  # bricks as a Slurm job array on a one-node cluster (SlurmBricksTest)
  munge slurmctld slurmd slurm-client
  # the image and the compose file (ImageTest)
  docker.io debootstrap docker-compose
  # the formats labs and simulators use: readers (HDF5, DICOM, PNG/JPEG stacks), Exodus II,
  # and the tools the tests load the outputs with
  libhdf5-dev libgdcm-dev libjpeg-dev libexodusii-dev calculix-ccx gmsh python3-h5py
  python3-netcdf4 python3-openvdb python3-nibabel python3-pydicom python3-pil
)
# Node and npm for the front-end: Debian's, unless the machine has its own.
command -v npm >/dev/null || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

build_dir=${SHEETMESH_BUILD_DIR:-build}
asserts=${SHEETMESH_ASSERTS:-OFF}
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [ ! -f "$build_dir/build.ninja" ] ||
   ! grep -q "^SHEETMESH_ASSERTS:BOOL=$asserts\$" "$build_dir/CMakeCache.txt"; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSHEETMESH_ASSERTS="$asserts" \
    "${launcher[@]}" >/dev/null
fi
cmake --build "$build_dir" -j "$(nproc)"
