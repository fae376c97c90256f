# Shared by the deploy tests (tests/deploy/README.md): skipping with a reason, a fresh Debian 12
# root filesystem made by mmdebstrap (cached per build folder), chroots with /proc and /dev, and
# the farm's .deb built by cpack from the build folder. Sourced, never run.

# Exit 77 (ctest's skip) with the reason as the first line of output.
skip() {
  echo "SKIP: $*"
  exit 77
}

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

require_root() {
  [ "$(id -u)" -eq 0 ] || skip "$1 needs root (chroot, mount)"
}

require_tool() {
  command -v "$1" >/dev/null 2>&1 || skip "$1 is not installed (deploy/install-deps.sh --deploy installs it)"
}

: "${FARM_SOURCE_DIR:?run through ctest, which sets FARM_SOURCE_DIR}"
: "${FARM_BUILD_DIR:?run through ctest, which sets FARM_BUILD_DIR}"
deploy_cache="$FARM_BUILD_DIR/deploy-cache"
mkdir -p "$deploy_cache"

# The path of a tarball of a minimal Debian 12 (mmdebstrap's apt variant plus the packages named),
# made once per set of packages and reused: concurrent tests wait on one lock.
debian_rootfs_tar() {
  local include="${1:-}"
  local key
  key=$(printf '%s' "$include" | sha256sum | cut -c1-12)
  local tar="$deploy_cache/bookworm-$key.tar"
  (
    flock 9
    if [ ! -s "$tar" ]; then
      local args=(--variant=apt --format=tar --quiet --skip=cleanup/apt/lists)
      [ -n "$include" ] && args+=("--include=$include")
      mmdebstrap "${args[@]}" bookworm "$tar.part" http://deb.debian.org/debian >&2 \
        && mv "$tar.part" "$tar"
    fi
  ) 9>"$deploy_cache/rootfs.lock"
  [ -s "$tar" ] || fail "mmdebstrap could not make a Debian 12 root filesystem"
  echo "$tar"
}

# Unpacks a fresh Debian 12 root filesystem into DIR, mounted as chroot_from_tar says.
chroot_fresh() {
  local dir="$1" include="${2:-}"
  local tar
  tar=$(debian_rootfs_tar "$include") || exit 1
  chroot_from_tar "$dir" "$tar"
}

# Unpacks the root filesystem tarball TAR into DIR, with this machine's resolver and added CAs,
# and mounts what programs in it expect (chroot_mount).
chroot_from_tar() {
  local dir="$1" tar="$2"
  mkdir -p "$dir"
  tar -C "$dir" -xf "$tar"
  cp /etc/resolv.conf "$dir/etc/resolv.conf"
  # The CAs this machine adds (an egress proxy's, say), so that HTTPS from inside (pip) works as
  # it does here; ca-certificates folds them into the chroot's bundle when it is installed.
  mkdir -p "$dir/usr/local/share/ca-certificates"
  cp /usr/local/share/ca-certificates/*.crt "$dir/usr/local/share/ca-certificates/" 2>/dev/null || true
  chroot_mount "$dir"
}

# Mounts /proc and /dev into the root filesystem DIR; chroot_cleanup (set as an EXIT trap by the
# caller) unmounts them.
chroot_mount() {
  local dir="$1"
  mount -t proc proc "$dir/proc"
  mount --rbind /dev "$dir/dev"
  mount --make-rslave "$dir/dev"
  chroot_mounted+=("$dir")
}

chroot_mounted=()
chroot_cleanup() {
  local dir
  for dir in "${chroot_mounted[@]}"; do
    umount -R "$dir/dev" 2>/dev/null || umount -l "$dir/dev" 2>/dev/null || true
    umount "$dir/proc" 2>/dev/null || umount -l "$dir/proc" 2>/dev/null || true
  done
  chroot_mounted=()
}

# Runs a command as root inside the chroot DIR, in a clean environment.
in_chroot() {
  local dir="$1"
  shift
  chroot "$dir" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 \
    DEBIAN_FRONTEND=noninteractive "$@"
}

# The path of the farm's .deb, made by cpack from the build folder when it is missing or older
# than the farm binary.
farm_deb() {
  local out="$deploy_cache/deb"
  (
    flock 9
    local deb
    deb=$(ls "$out"/renderfarm_*.deb 2>/dev/null | head -1)
    if [ -z "$deb" ] || [ "$FARM_BINARY" -nt "$deb" ]; then
      rm -rf "$out" && mkdir -p "$out"
      (cd "$FARM_BUILD_DIR" && cpack -G DEB -B "$out" >&2) || exit 1
    fi
  ) 9>"$deploy_cache/deb.lock" || fail "cpack could not make the .deb"
  ls "$out"/renderfarm_*.deb | head -1
}
