#!/usr/bin/env bash
# Gradescope runs this once, as root, while it builds the autograder's image; the archive made by
# deploy/gradescope/make-autograder.sh is unpacked in /autograder/source. It installs the farm and
# checks the pre-rendered references, so that grading a submission later only compares images.
#
# Which base image (Gradescope's "Base Image OS / Version"):
# - Ubuntu 24.04: the one to choose on Gradescope. The farm is built here from the source the
#   archive carries (farm-source.tar.gz), with Ubuntu's packages of the libraries it links
#   (deploy/install-deps.sh --build: the package names are Debian 12's), and installed as
#   /usr/local/bin/farm. That takes minutes, once per image.
# - Debian 12: the farm's .deb is installed. Its Depends name bookworm's libraries by soname, so
#   it installs nowhere else (tests/deploy/gradescope_autograder_test.sh grades on Debian 12).
# - Anything else stops here. Gradescope's default, Ubuntu 22.04, has older libraries (OpenEXR
#   2.5, gRPC 1.30, protobuf 3.12, fmt 8) than the farm is written for.
set -euo pipefail
cd /autograder/source
started=$SECONDS
export DEBIAN_FRONTEND=noninteractive

. /etc/os-release
system="${ID:-unknown}-${VERSION_ID:-unknown}"
case "$system" in
  debian-12)
    apt-get update
    # bubblewrap is the sandbox `farm grade` runs a student's program in (a rubric's "run"
    # tasks); the .deb only recommends it, and recommends ffmpeg too, which grading never uses.
    apt-get install -y --no-install-recommends ./@DEB@ bubblewrap
    farm=/usr/bin/farm
    ;;
  ubuntu-24.04)
    work=$(mktemp -d /tmp/farm-build.XXXXXX)
    mkdir "$work/src"
    tar -C "$work/src" -xzf farm-source.tar.gz
    apt-get update
    apt-get install -y --no-install-recommends bubblewrap
    # The build group only: the runtime group's ffmpeg (a job's video) is not used by grading.
    bash "$work/src/deploy/install-deps.sh" --build
    echo "setup.sh: packages installed after $((SECONDS - started)) s"
    # The farm target alone, without the test suite; warnings are not errors here (the release
    # preset makes them errors), as this compiler is not the one the project checks with.
    cmake -S "$work/src" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFARM_BUILD_TESTS=OFF
    cmake --build "$work/build" --target farm
    install -m 755 "$work/build/server/farm" /usr/local/bin/farm
    rm -rf "$work"  # the image keeps the binary only
    farm=/usr/local/bin/farm
    echo "setup.sh: farm built after $((SECONDS - started)) s"
    ;;
  *)
    echo "setup.sh: this is ${PRETTY_NAME:-an unknown system} ($system); this autograder installs" \
      "the farm on Ubuntu 24.04 (built from farm-source.tar.gz) or Debian 12 (the .deb) only." \
      "On Gradescope, set the autograder's Base Image OS to Ubuntu and Version to 24.04." >&2
    exit 1
    ;;
esac
"$farm" --version

# The references shipped in the archive, intact: one missing would be rendered at every submission.
(cd grading && sha256sum --check --quiet references.sha256)
echo "setup.sh: $("$farm" --version) installed as $farm on $system after $((SECONDS - started)) s;" \
  "$(wc -l <grading/references.sha256) pre-rendered reference files present"
