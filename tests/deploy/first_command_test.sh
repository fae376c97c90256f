#!/usr/bin/env bash
# Deploy.first_command (issue #34): README command 1 as a new user runs it, on a fresh Debian 12
# (an mmdebstrap chroot with git and nothing else): a clone of this repository's HEAD, the command
# copied out of README.md, timed, and the cow it renders compared with the build tree's. It
# installs the build packages and compiles farm from nothing (about five minutes on 2 cores), so
# it runs only when asked: FARM_DEPLOY_FIRST_COMMAND=1 ctest -R Deploy.first_command.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
[ "${FARM_DEPLOY_FIRST_COMMAND:-0}" = 1 ] \
  || skip "README command 1 from a fresh machine takes ~5 minutes: run with FARM_DEPLOY_FIRST_COMMAND=1"
require_root "a fresh chroot"
require_tool mmdebstrap
[ -d "$FARM_SHARED_ASSETS" ] || skip "the cow lives in $FARM_SHARED_ASSETS, which is absent"

work=$(mktemp -d /tmp/farm-first-command.XXXXXX)
cleanup() {
  umount "$work/root/work/shared" 2>/dev/null || true
  chroot_cleanup
  rm -rf "$work"
}
trap cleanup EXIT

# README command 1, exactly: the first fenced line after "**1.".
command=$(awk '/^\*\*1\./ { found = 1 } found && /^deploy\/install-deps.sh/ { print; exit }' "$FARM_SOURCE_DIR/README.md")
[ -n "$command" ] || fail "README.md has no command 1 starting with deploy/install-deps.sh"
echo "README command 1: $command"

root="$work/root"
chroot_fresh "$root" git
git -C "$FARM_SOURCE_DIR" bundle create "$work/head.bundle" HEAD 2>/dev/null
mkdir -p "$root/work/shared"
mount --bind -o ro "$(readlink -f "$FARM_SHARED_ASSETS/..")" "$root/work/shared"
cp "$work/head.bundle" "$root/tmp/"
in_chroot "$root" git -c advice.detachedHead=false clone -q /tmp/head.bundle /work/main

start=$SECONDS
# xtrace stamps each step of the command with the seconds since it began.
in_chroot "$root" bash -c "PS4='+ [\$SECONDS s] '; set -x; cd /work/main && $command" >"$work/command.log" 2>&1 \
  || { tail -30 "$work/command.log"; fail "README command 1 failed on a fresh Debian 12"; }
seconds=$((SECONDS - start))
printf 'README command 1 on a fresh Debian 12 chroot: %d s (%d min %02d s)\n' "$seconds" $((seconds / 60)) $((seconds % 60))
grep -E '^\+ \[[0-9]+ s\] (deploy|cmake|./build)' "$work/command.log" | cut -c1-120 || true

"$FARM_BINARY" render "$FARM_SOURCE_DIR/jobs/cow.json" --asset-root "$FARM_SHARED_ASSETS" \
  --out "$work/cow.exr" --preview none --quiet
"$FARM_BINARY" compare "$work/cow.exr" "$root/work/main/out/cow.exr" --metric exact \
  || fail "the fresh machine's cow differs from the build tree's"
echo "PASS: command 1 rendered the cow, bit-identical to the build tree's"
