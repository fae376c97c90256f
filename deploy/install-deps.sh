#!/usr/bin/env bash
# Installs the Debian 12 packages the build, the tests, the benchmarks and the deploy tests need,
# by group (--help).
# Non-interactive and idempotent: safe to run on every CI run and on a fresh machine.
set -euo pipefail

usage() {
  cat <<'USAGE'
Usage: deploy/install-deps.sh [--build] [--runtime] [--test] [--deploy] [--all]

Installs the Debian 12 packages of the groups named (apt-get, as root or through sudo); with no
group, all of them (what CI and the test suite need). Idempotent: present packages are skipped.

  --build    compile `farm`: the toolchain and the -dev packages of every library it links
  --runtime  the programs `farm` runs: ffmpeg (a job's video), bubblewrap (`farm grade`'s sandbox)
  --test     the test suite and benchmarks: GoogleTest, OpenImageIO, PostgreSQL, Chromium, clang,
             the Python client's build, and the Python test tools in a venv at build/test-venv
  --deploy   the deploy tests (tests/deploy): mmdebstrap, podman, Slurm, munge, systemd, kubectl

README command 1 installs --build only: what it takes to build `farm` and render a job.
USAGE
}

# Also what deploy/gradescope/setup.sh installs on Ubuntu 24.04 before building farm there: keep
# to names both distributions have (tests/deploy/gradescope_ubuntu_test.sh).
build_packages=(
  # toolchain (dpkg-dev, in build-essential, brings dpkg-shlibdeps for `cpack -G DEB`)
  build-essential cmake ninja-build pkg-config git ca-certificates
  # file: dpkg-shlibdeps reads the binary with it when `cpack -G DEB` computes the Depends
  file
  # renderer (TBB, which Embree's CMake config asks for, comes with libembree-dev)
  libembree-dev libopenexr-dev libimath-dev libpng-dev libjpeg-dev libdeflate-dev libisal-dev
  libtinygltf-dev libassimp-dev libglm-dev
  # service
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libsqlite3-dev libssl-dev
  # the PostgreSQL job store (issue #18): libpq to talk to it
  libpq-dev
  # command line, config, logging
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  # XML (the COLLADA files a job's models name)
  libpugixml-dev
  # the scheduler's dashboard and JSON API (`farm scheduler --http`)
  libcpp-httplib-dev
)

runtime_packages=(
  # the grading sandbox (server/grade/sandbox.cpp): bwrap runs a student's program; setpriv,
  # which drops it to a user of its own, comes with util-linux (essential, always installed)
  bubblewrap
  # a job's output.video (server/common/video_encoder.cpp): ffmpeg, run as a program, encodes
  # the frames' previews (H.264, VP9); ffprobe, in the same package, reads the videos in tests
  ffmpeg
)

test_packages=(
  # OpenImageIO: farm_oiio_tests read previews back with it, and idiff is the threshold
  # metric's anchor
  libopenimageio-dev openimageio-tools
  # the PostgreSQL server, which the tests start in a temporary folder of their own
  # (tests/support/postgres_server.h)
  postgresql
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
  # the browser the dashboard's test drives
  chromium chromium-driver python3-selenium
  # Prometheus's own parser of its text format, which reads the dashboard's /metrics in its test
  python3-prometheus-client
)

deploy_packages=(
  # fresh Debian 12 root filesystems for the chroot tests, and the container image's base
  mmdebstrap
  # the image (deploy/container): podman builds and runs it; runc, because crun cannot run under
  # hybrid cgroups (tests/deploy/README.md)
  podman buildah runc
  # Compose's own readers of deploy/compose.yaml
  docker-compose podman-compose
  # a one-node Slurm (deploy/slurm) and its authentication
  slurm-wlm munge
  # systemd-analyze verify (deploy/systemd), and strace, which checks the units' system calls
  # against their SystemCallFilter
  systemd strace
  # the Gradescope archive (deploy/gradescope)
  zip unzip
)

groups=()
for arg in "$@"; do
  case "$arg" in
    --build | --runtime | --test | --deploy) groups+=("${arg#--}") ;;
    --all) groups+=(build runtime test deploy) ;;
    -h | --help) usage; exit 0 ;;
    *) echo "install-deps: unknown option '$arg'" >&2; usage >&2; exit 2 ;;
  esac
done
[ ${#groups[@]} -eq 0 ] && groups=(build runtime test deploy)

packages=()
for group in "${groups[@]}"; do
  case "$group" in
    build) packages+=("${build_packages[@]}") ;;
    runtime) packages+=("${runtime_packages[@]}") ;;
    test) packages+=("${test_packages[@]}") ;;
    deploy)
      packages+=("${deploy_packages[@]}")
      # kubectl renders deploy/k8s; Debian's package is kubernetes-client, which would clash
      # with a kubectl already installed another way (a cloud SDK's), so only when there is none
      command -v kubectl >/dev/null 2>&1 || packages+=(kubernetes-client)
      ;;
  esac
done

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

case " ${groups[*]} " in *" test "*) ;; *) exit 0 ;; esac

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
