#!/usr/bin/env bash
# Installs every Debian 12 package the build, the tests and the benchmarks need.
# Non-interactive and idempotent: safe to run on every CI run and on a fresh machine.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  # renderer (TBB, which Embree's CMake config asks for, comes with libembree-dev)
  libembree-dev libopenexr-dev libimath-dev libpng-dev libjpeg-dev
  libtinygltf-dev libassimp-dev libglm-dev
  # OpenImageIO: farm_oiio_tests read previews back with it; `farm compare` reads
  # images of any format, and idiff is its threshold metric's anchor
  libopenimageio-dev openimageio-tools
  # service
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libsqlite3-dev libssl-dev
  # command line, config, logging
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  # XML (the COLLADA files a job's models name)
  libpugixml-dev
  # the grading sandbox (server/grade/sandbox.cpp): bwrap runs a student's program; setpriv,
  # which drops it to a user of its own, comes with util-linux (essential, always installed)
  bubblewrap
  # a job's output.video (server/common/video_encoder.cpp): ffmpeg, run as a program, encodes
  # the frames' previews (H.264, VP9); ffprobe, in the same package, reads the videos in tests
  ffmpeg
  # the PostgreSQL job store (issue #18): libpq to talk to it, and the server, which the tests
  # start in a temporary folder of their own (tests/support/postgres_server.h)
  libpq-dev postgresql
  # the multi-host test (tests/integration/multi_host_farm_test.cpp): `ip` makes its hosts as
  # network namespaces on a bridge
  iproute2
  # tests and benchmarks
  libgtest-dev libbenchmark-dev python3 python3-venv
  # fuzzing (tests/fuzz, the `fuzz` preset): clang, and libFuzzer with the sanitizer runtimes,
  # which Debian ships in compiler-rt's package rather than a libfuzzer one of its own
  clang-14 libclang-rt-14-dev
  # the Python client package (proto/python: stubs generated from proto/farm.proto by grpc_tools
  # when pip builds it; python3-wheel: setuptools 66 builds wheels with it)
  python3-grpcio python3-grpc-tools python3-protobuf python3-setuptools python3-wheel python3-pip
  # the scheduler's dashboard (`farm scheduler --http`), and the browser its test drives
  libcpp-httplib-dev chromium chromium-driver python3-selenium
  # Prometheus's own parser of its text format, which reads the dashboard's /metrics in its test
  python3-prometheus-client
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The Python test tools (PyPI, pinned): a venv of Debian's python3 at build/test-venv, which the
# tests find through CMake (FARM_TEST_PYTHON). Reinstalled only when the pins change.
repo="$(cd "$(dirname "$0")/.." && pwd)"
venv="$repo/build/test-venv"
requirements="$repo/tests/python/requirements-test.txt"
stamp="$venv/.requirements-test.txt"
if ! cmp -s "$requirements" "$stamp" 2>/dev/null; then
  echo "install-deps: Python test tools into $venv"
  rm -rf "$venv"
  /usr/bin/python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$requirements"
  cp "$requirements" "$stamp"
else
  echo "install-deps: Python test tools present in $venv"
fi
