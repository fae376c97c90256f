#!/usr/bin/env bash
# Deploy.container_image (issue #34 item 3): deploy/container/build-image.sh builds the image from
# the build folder's .deb (the compile in the Containerfile's build stage takes ~10 minutes on 2
# cores, too long for CI: run `deploy/container/build-image.sh --from-source` by hand for that
# path), then the image is checked for what it promises:
# - the example job it ships renders inside it to an EXR bit-identical to $FARM_BINARY's;
# - it runs as the non-root user `farm`, with `farm` as its entrypoint and a HEALTHCHECK;
# - its default command is a scheduler that its HEALTHCHECK (`farm health`) finds SERVING.
# Where podman cannot run containers even with deploy/container/sandbox-containers.conf, it prints
# podman's error and proves the image's root filesystem instead: exported, entered with chroot as
# the farm user, the job rendered there. FARM_TEST_CONTAINER_CHROOT=1 takes that path on purpose.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
require_tool podman
require_tool mmdebstrap

image="localhost/renderfarm:ctest"
scheduler="farm-ctest-scheduler-$$"
work="$(mktemp -d)"
chmod 755 "$work"
cleanup() {
  podman rm --force --ignore "$scheduler" >/dev/null 2>&1 || true
  podman rmi --force "$image" >/dev/null 2>&1 || true  # the cached Debian base stays
  chroot_cleanup
  rm -rf --one-file-system "$work"
}
trap cleanup EXIT

# The image, from the .deb (the base image and the .deb are cached in the build folder).
deb="$(farm_deb)"
echo "building $image from $(basename "$deb")"
if ! FARM_IMAGE_CACHE="$deploy_cache" "$FARM_SOURCE_DIR/deploy/container/build-image.sh" \
  --deb "$deb" --tag "$image" >"$work/build.log" 2>&1; then
  tail -n 40 "$work/build.log"
  fail "build-image.sh could not build the image (the log's end is above)"
fi
grep '^build-image:' "$work/build.log" | sed 's/^/  /'

# What the image says about itself.
entrypoint="$(podman image inspect --format '{{json .Config.Entrypoint}}' "$image")"
[ "$entrypoint" = '["farm"]' ] || fail "the image's entrypoint is $entrypoint, not [\"farm\"]"
health="$(podman image inspect --format '{{json .HealthCheck.Test}}' "$image")"
case "$health" in
  '["CMD","farm","health",'*) ;;
  *) fail "the image has no HEALTHCHECK running farm health (it says: $health)" ;;
esac
config_user="$(podman image inspect --format '{{.Config.User}}' "$image")"
[ "$config_user" = farm ] || fail "the image runs as '$config_user', not as the user farm"
echo "image config: entrypoint $entrypoint, user $config_user, healthcheck $health"

# The job the .deb ships, rendered outside by the build tree's farm: the reference.
job_in_image=/usr/share/renderfarm/jobs/cornell.json
mkdir -p "$work/host" "$work/out"
chmod 777 "$work/out"  # written by the image's farm user
"$FARM_BINARY" render "$FARM_SOURCE_DIR/jobs/cornell.json" --out "$work/host/cornell.exr" \
  --preview none --quiet

# Can containers run here? As podman is configured, else with the sandbox's settings.
runs=yes
if [ "${FARM_TEST_CONTAINER_CHROOT:-0}" = 1 ]; then
  runs=no
  echo "FARM_TEST_CONTAINER_CHROOT=1: proving the root filesystem instead of running the image"
elif ! error="$(podman run --rm --no-healthcheck --entrypoint true "$image" 2>&1)"; then
  echo "podman run, as configured, fails here: $error"
  export CONTAINERS_CONF="$FARM_SOURCE_DIR/deploy/container/sandbox-containers.conf"
  if error="$(podman run --rm --no-healthcheck --entrypoint true "$image" 2>&1)"; then
    echo "podman run works with CONTAINERS_CONF=$CONTAINERS_CONF"
  else
    echo "podman run fails with CONTAINERS_CONF=$CONTAINERS_CONF too: $error"
    runs=no
  fi
fi

if [ "$runs" = yes ]; then
  uid="$(podman run --rm --no-healthcheck --entrypoint id "$image" -u)"
  [ "$uid" != 0 ] || fail "the container runs as root"
  echo "the container runs as uid $uid"

  podman run --rm --no-healthcheck -v "$work/out:/out" "$image" \
    render "$job_in_image" --out /out/cornell.exr --preview none --quiet \
    || fail "farm render failed inside the image"
else
  require_root
  # The image's files as a folder: a container made (never started) and exported.
  podman create --name "$scheduler" "$image" >/dev/null
  mkdir "$work/rootfs"
  podman export "$scheduler" | tar -C "$work/rootfs" -xf -
  podman rm "$scheduler" >/dev/null
  chroot_mount "$work/rootfs"
  mkdir "$work/rootfs/out"
  trap 'umount "$work/rootfs/out" 2>/dev/null || true; cleanup' EXIT
  mount --bind "$work/out" "$work/rootfs/out"
  uid="$(chroot --userspec=farm:farm "$work/rootfs" id -u)"
  [ "$uid" != 0 ] || fail "the image's farm user is root"
  echo "the image's farm user is uid $uid"
  chroot --userspec=farm:farm "$work/rootfs" /usr/bin/env -i PATH=/usr/bin:/bin HOME=/var/lib/farm \
    farm render "$job_in_image" --out /out/cornell.exr --preview none --quiet \
    || fail "farm render failed in the image's root filesystem"
fi

# Bit for bit: the pixels (farm compare --metric exact), and whether the files are the same bytes.
"$FARM_BINARY" compare "$work/host/cornell.exr" "$work/out/cornell.exr" --metric exact \
  || fail "the EXR rendered in the image differs from the build tree's"
cmp "$work/host/cornell.exr" "$work/out/cornell.exr" \
  || fail "the EXRs have the same pixels but not the same bytes"
echo "the image's render of $job_in_image is bit-identical to the build tree's"

[ "$runs" = yes ] || { echo "PASS (root filesystem; containers cannot run here)"; exit 0; }

# The default command: a scheduler, its tokens file given as the secret it expects. Its
# HEALTHCHECK is run by hand (--health-interval disable: no timer; podman 4.3 still tries to make
# one with systemd and logs that it cannot where there is none, hence run.err).
# (`farm token` prints the token on stdout, and on stderr a note then the file's line.)
"$FARM_BINARY" token ctest --roles admin 2>&1 >/dev/null | tail -n 1 >"$work/farm-tokens"
chmod 644 "$work/farm-tokens"
podman run --detach --name "$scheduler" --health-interval disable \
  -v "$work/farm-tokens:/run/secrets/farm-tokens:ro" "$image" >/dev/null 2>"$work/run.err" \
  || { cat "$work/run.err"; fail "podman could not start the scheduler's container"; }
deadline=$((SECONDS + 60))
until podman healthcheck run "$scheduler" >/dev/null 2>&1; do
  if [ "$(podman inspect --format '{{.State.Running}}' "$scheduler")" != true ]; then
    podman logs "$scheduler" | tail -n 20
    fail "the scheduler's container stopped (its log's end is above)"
  fi
  [ $SECONDS -lt $deadline ] || { podman logs "$scheduler" | tail -n 20; fail "the HEALTHCHECK never passed in 60 s"; }
  sleep 1
done
echo "podman healthcheck run: healthy"
answer="$(podman exec "$scheduler" farm health --scheduler localhost:50051)"
[ "$answer" = "localhost:50051: SERVING" ] || fail "farm health said '$answer'"
echo "podman exec farm health: $answer"
podman logs "$scheduler" >"$work/scheduler.log" 2>&1
grep -q '^scheduler listening on 0.0.0.0:50051$' "$work/scheduler.log" \
  || fail "the default command did not start a scheduler on 0.0.0.0:50051"
# ...and the check can fail: nothing listens on port 50052.
if podman exec "$scheduler" farm health --scheduler localhost:50052 --timeout 2s >/dev/null 2>&1; then
  fail "farm health passed for a port nothing listens on"
fi
podman stop --time 20 "$scheduler" >/dev/null
echo "PASS"
