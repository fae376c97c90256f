#!/bin/bash
# Thread scaling on a lent machine that has none of Debian's packages (issue #37, item 4: `farm
# bench raster`, `bench rt` and `bench path` at 1, 2, 4, 8 and 16 threads).
#
#   tools/device_scaling.sh pack [ARCHIVE]   here: farm (stripped), every shared library it loads
#                                            (the loader and libc too) and the bench models, in one
#                                            xz archive (default build/device/farm-device.tar.xz,
#                                            under the 64 MiB a device call carries)
#   tools/device_scaling.sh run [ARCHIVE]    there, from the repository root: unpacks it and runs
#                                            the benches through the packed loader, each bounded by
#                                            `timeout`, their output under $OUT (or ./device-out)
#
# The packed loader runs the packed libraries whatever the machine's own are, so the figures are
# those of the build measured here. `bench render` is left out: it starts `farm` again as a child,
# which under an explicit loader would be the loader.
set -euo pipefail

mode=${1:-}
archive=${2:-build/device/farm-device.tar.xz}
farm_binary=${FARM_BINARY:-build/release/server/farm}
assets=${FARM_ASSETS:-../shared/assets}
threads=${THREADS:-1,2,4,8,16}

case "$mode" in
  pack)
    stage=$(mktemp -d)
    trap 'rm -rf "$stage"' EXIT
    mkdir -p "$stage/farm-device/lib" "$stage/farm-device/assets/dae"
    strip -o "$stage/farm-device/farm" "$farm_binary"
    # Every library the dynamic loader resolves for farm, and the loader itself.
    ldd "$farm_binary" | awk '/=>/ {print $3} /^\t\/.*ld-linux/ {print $1}' | while read -r lib; do
      [ -n "$lib" ] && cp -L "$lib" "$stage/farm-device/lib/"
    done
    for model in cow bunny CBbunny; do cp "$assets/dae/$model.dae" "$stage/farm-device/assets/dae/"; done
    mkdir -p "$(dirname "$archive")"
    tar -C "$stage" -cf - farm-device | xz -T0 -6 > "$archive"
    ls -l "$archive"
    ;;
  run)
    out=${OUT:-device-out}
    mkdir -p "$out" build/device
    tar -C build/device -xJf "$archive"
    root=build/device/farm-device
    loader=$(ls "$root"/lib/ld-linux-x86-64.so.*)
    farm() { "$loader" --library-path "$root/lib" "$root/farm" "$@"; }
    { nproc; lscpu | grep -E 'Model name|^CPU\(s\)|Flags' | cut -c1-200; } > "$out/machine.txt" 2>&1 || true
    bench() {  # name, seconds, farm arguments...
      local name=$1 seconds=$2
      shift 2
      echo "== $name: farm $*" | tee -a "$out/summary.txt"
      timeout "$seconds" "$loader" --library-path "$root/lib" "$root/farm" "$@" > "$out/$name.txt" 2>&1 || \
        echo "   exit $? (timeout $seconds s)" | tee -a "$out/summary.txt"
      tail -n 25 "$out/$name.txt" >> "$out/summary.txt"
    }
    farm --version > "$out/version.txt" 2>&1
    bench raster 120 bench raster --model "$root/assets/dae/cow.dae" --threads "$threads" --frames 5
    bench path 200 bench path --assets "$root/assets" --scene cornell --threads "$threads"
    bench rt 200 bench rt --assets "$root/assets" --threads "$threads" --rays 200000 --repeats 1
    ;;
  *)
    sed -n '2,15p' "$0"
    exit 2
    ;;
esac
