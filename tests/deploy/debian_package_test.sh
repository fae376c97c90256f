#!/usr/bin/env bash
# Deploy.debian_package (issue #34): the .deb that `cpack -G DEB` makes from the build folder
# installs with apt into a fresh Debian 12 (an mmdebstrap chroot: nothing of this machine's
# packages), pulls in its libraries from the Depends that dpkg-shlibdeps computed, and renders an
# example job there bit-identical to the build tree's farm.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
require_root "installing into a chroot"
require_tool mmdebstrap
require_tool cpack
require_tool dpkg-deb

work=$(mktemp -d /tmp/farm-deb-test.XXXXXX)
cleanup() {
  chroot_cleanup
  rm -rf "$work"
}
trap cleanup EXIT

deb=$(farm_deb)
echo "package: $deb"

# What the package declares: a Depends line computed from the binary, naming the libraries farm
# links (not a hand-written list), and the files where the issue puts them.
depends=$(dpkg-deb -f "$deb" Depends)
echo "Depends: $depends"
for library in libembree3 libopenexr libassimp libpq5 libsqlite3 libdeflate0 libisal2; do
  grep -q "$library" <<<"$depends" || fail "Depends does not name $library: $depends"
done
# gRPC, protobuf and abseil are linked in (FARM_STATIC_GRPC, docs/architecture.md 9.1): a Depends
# naming them would pull in packages the binary never loads.
for library in libgrpc libprotobuf libabsl; do
  if grep -q "$library" <<<"$depends"; then fail "Depends names $library, which farm links statically: $depends"; fi
done
contents=$(dpkg-deb -c "$deb")
for file in ./usr/bin/farm ./usr/share/renderfarm/jobs/cornell.json ./usr/share/renderfarm/jobs/assets/ \
  ./usr/share/doc/renderfarm/README.md ./usr/share/doc/renderfarm/architecture.md; do
  grep -q " $file\$" <<<"$contents" || grep -q " $file -> " <<<"$contents" || fail "the package holds no $file"
done

root="$work/root"
chroot_fresh "$root"
in_chroot "$root" test ! -e /usr/bin/farm || fail "the fresh chroot already has a farm"
cp "$deb" "$root/tmp/"
echo "installing $(basename "$deb") into a fresh Debian 12 chroot"
in_chroot "$root" apt-get update -qq
in_chroot "$root" apt-get install -y -qq --no-install-recommends "/tmp/$(basename "$deb")" >"$work/apt.log" 2>&1 \
  || { tail -20 "$work/apt.log"; fail "apt-get install of the .deb failed"; }

version_inside=$(in_chroot "$root" farm --version)
version_here=$("$FARM_BINARY" --version)
[ "$version_inside" = "$version_here" ] || fail "installed '$version_inside', built '$version_here'"

# Every job the package ships loads there: none reaches for a model it does not ship.
for job in $(in_chroot "$root" sh -c 'ls /usr/share/renderfarm/jobs/*.json'); do
  in_chroot "$root" farm info "$job" >/dev/null || fail "the packaged $job does not load"
done

# The example job as installed, rendered inside; the same job from the source tree, outside.
in_chroot "$root" farm render /usr/share/renderfarm/jobs/cornell.json --out /tmp/inside.exr --preview none --quiet
"$FARM_BINARY" render "$FARM_SOURCE_DIR/jobs/cornell.json" --out "$work/outside.exr" --preview none --quiet
"$FARM_BINARY" compare "$work/outside.exr" "$root/tmp/inside.exr" --metric exact \
  || fail "the installed farm's render differs from the build tree's"
echo "PASS: installed from $(basename "$deb") in a fresh chroot; its render is bit-identical"
