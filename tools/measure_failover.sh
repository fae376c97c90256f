#!/usr/bin/env bash
# Issue #18's failover figure: two schedulers on one PostgreSQL store (default lease, 10 s) send a
# path-traced job's units to the same two workers; one scheduler is killed (-9) mid-job. Prints how
# long after the kill the job's next unit was done, and when the survivor reaped the dead one's
# lease (its units queued again). Usage: tools/measure_failover.sh FARM_BINARY postgresql://URL
set -euo pipefail
farm=$1 store=$2
dir=$(mktemp -d)
trap 'kill $(cat "$dir"/*.pid) 2>/dev/null || true; sleep 1; rm -rf "$dir"' EXIT
here=$(cd "$(dirname "$0")/.." && pwd)
cp -r "$here/jobs/cornell_path.json" "$here/jobs/assets" "$dir/"
start() {  # NAME ARGS...: a server in the background, its address once it listens
  local name=$1; shift
  "$farm" "$@" >"$dir/$name.log" 2>&1 &
  echo $! >"$dir/$name.pid"
  for _ in $(seq 100); do
    grep -q "listening on" "$dir/$name.log" && break
    sleep 0.1
  done
  sed -n 's/.*listening on \([^ ]*\).*/\1/p' "$dir/$name.log" | head -1
}
w1=$(start w1 worker --listen 127.0.0.1:0 --threads 1 --cache-dir "$dir/w1")
w2=$(start w2 worker --listen 127.0.0.1:0 --threads 1 --cache-dir "$dir/w2")
a=$(start a scheduler --listen 127.0.0.1:0 --data-dir "$dir/data" --store "$store" --worker "$w1" --worker "$w2")
b=$(start b scheduler --listen 127.0.0.1:0 --data-dir "$dir/data" --store "$store" --worker "$w1" --worker "$w2")
id=$("$farm" submit --scheduler "$a" "$dir/cornell_path.json" --width 256 --height 192 --spp 512 --tile-size 16 2>/dev/null)
done_tiles() {  # units done so far; exits when the job ended otherwise than well
  local said
  said=$("$farm" status --scheduler "$b" "$id" | head -1)
  case "$said" in *": failed,"* | *": cancelled,"*) echo "job ended: $said" >&2; kill -TERM $$ ;; esac
  echo "$said" | sed -n 's/.*: [a-z]*, \([0-9]*\)\/.*/\1/p'
}
until [ "$(done_tiles)" -ge 20 ]; do sleep 0.1; done
before=$(done_tiles)
kill -9 "$(cat "$dir/a.pid")"
killed=$(date +%s.%N)
until [ "$(done_tiles)" -gt "$before" ]; do sleep 0.05; done
resumed=$(date +%s.%N)
until grep -q "its lease ran out" "$dir/b.log"; do sleep 0.05; done
reaped=$(date +%s.%N)
"$farm" watch --scheduler "$b" "$id" >/dev/null
echo "failover: scheduler killed at unit $before of $("$farm" status --scheduler "$b" "$id" | sed -n 's/.*, [0-9]*\/\([0-9]*\) .*/\1/p' | head -1);" \
  "next unit done $(awk "BEGIN{printf \"%.2f\", $resumed - $killed}") s later; the dead one's units queued again after $(awk "BEGIN{printf \"%.2f\", $reaped - $killed}") s;" \
  "job $("$farm" status --scheduler "$b" "$id" | sed -n 's/.*: \([a-z]*\), .*/\1/p' | head -1)"
