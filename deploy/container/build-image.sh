#!/usr/bin/env bash
# Builds the farm's container image (deploy/container/Containerfile) with podman, on a Debian 12
# base made here by mmdebstrap: no image registry is needed, only Debian's mirror.
set -euo pipefail

usage() {
  cat <<'USAGE'
Usage: deploy/container/build-image.sh [--from-source | --deb PATH] [--tag TAG] [--base IMAGE]

  --from-source  compile `farm` inside the image's build stage (the default; 7-13 min on 2 cores)
  --deb PATH     install this renderfarm_*.deb (`cpack -G DEB` in a build folder) instead of
                 compiling: the build stage is skipped
  --tag TAG      the image's name (default localhost/renderfarm:latest)
  --base IMAGE   build on this Debian 12 image (e.g. docker.io/library/debian:bookworm) rather
                 than on localhost/renderfarm-base:bookworm, which is made with mmdebstrap when
                 podman does not have it yet (its tarball is cached in $FARM_IMAGE_CACHE, by
                 default ~/.cache/renderfarm)

Runs podman as is; where that cannot start a container (sandboxes without CAP_SYS_RESOURCE or
with hybrid cgroups), it says why and builds with deploy/container/sandbox-containers.conf; where
that fails too, with buildah's chroot isolation (an image that cannot be run on this machine).
USAGE
}

here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
deb=""
tag="localhost/renderfarm:latest"
base=""
while [ $# -gt 0 ]; do
  case "$1" in
    --from-source) deb="" ;;
    --deb) deb="$(realpath "${2:?--deb needs a path}")"; shift ;;
    --tag) tag="${2:?--tag needs a name}"; shift ;;
    --base) base="${2:?--base needs an image}"; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "build-image: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
  shift
done
say() { echo "build-image: $*" >&2; }
[ -z "$deb" ] || [ -f "$deb" ] || { say "no such .deb: $deb"; exit 2; }

# 1. The base: a minimal Debian 12 (minbase: what the registry's debian:bookworm holds), imported.
if [ -z "$base" ]; then
  base="localhost/renderfarm-base:bookworm"
  if ! podman image exists "$base"; then
    cache="${FARM_IMAGE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/renderfarm}"
    tar="$cache/bookworm-minbase.tar"
    if [ ! -s "$tar" ]; then
      say "making the Debian 12 base with mmdebstrap into $tar"
      mkdir -p "$cache"
      mmdebstrap --variant=minbase --format=tar --quiet bookworm "$tar.part" http://deb.debian.org/debian
      mv "$tar.part" "$tar"
    fi
    podman import --quiet --change 'ENV=PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
      --change 'CMD=["bash"]' "$tar" "$base" >/dev/null
    say "imported $tar as $base"
  fi
fi

# 2. Can podman run a container here as configured? Builds run their RUN steps the same way.
isolation=()
if ! error=$(podman run --rm "$base" true 2>&1); then
  say "podman cannot run a container with its configuration here:"
  printf '  %s\n' "$error" >&2
  export CONTAINERS_CONF="$here/sandbox-containers.conf"
  say "retrying with CONTAINERS_CONF=$CONTAINERS_CONF (runc, the caller's ulimits)"
  if ! error=$(podman run --rm "$base" true 2>&1); then
    say "podman cannot run a container with that either:"
    printf '  %s\n' "$error" >&2
    # Buildah's chroot isolation needs no OCI runtime: the image is built all the same, though
    # it cannot be run on this machine.
    say "building with --isolation chroot instead; the image will not run here"
    isolation=(--isolation chroot)
  fi
fi

# 3. The image. With --deb, a folder holding deb/<the .deb> stands in for the `package` stage.
args=(build --format docker --file "$here/Containerfile" --ignorefile "$here/.containerignore"
  --build-arg "BASE=$base" --tag "$tag" "${isolation[@]}")
context=""
trap '[ -z "$context" ] || rm -rf "$context"' EXIT
if [ -n "$deb" ]; then
  context="$(mktemp -d)"
  mkdir "$context/deb"
  cp "$deb" "$context/deb/"
  args+=(--build-context "package=$context")
  say "building $tag from $(basename "$deb") on $base"
else
  say "building $tag from source on $base"
fi
podman "${args[@]}" "$repo"
say "built $tag"
