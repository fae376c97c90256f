#!/bin/bash
# Deploy.systemd_units: deploy/systemd's units are valid, hardened, and their hardening admits
# what the farm does.
#
#  1. `systemd-analyze verify` of farm-scheduler.service, farm-worker@.service (and an instance),
#     and of the scheduler with the example drop-in, each a copy whose ExecStart names the farm
#     binary under test instead of the .deb's /usr/bin/farm (verify wants it to exist). verify
#     exits 0 on a misspelt key or a bad value, so any word it says is a failure; a copy broken on
#     purpose (ProtectSystem=strictt) must make it say something, or the check proves nothing.
#  2. `systemd-analyze security --offline=yes`: the exposure of each, printed (and below 5, the
#     start of MEDIUM).
#  3. The units' command lines, run: ExecStart with its specifiers (%S %C %d %i) and variables
#     (Environment=, then renderfarm.default as /etc/default/renderfarm) resolved, with the
#     credentials LoadCredential= names made by deploy/compose/make-secrets.sh (mode 0400, the
#     service's), as an unprivileged user (setpriv), from /, with UMask=, in a mount namespace
#     laid out as the unit's file-system settings make it: every mount read-only but the
#     StateDirectory or CacheDirectory (ProtectSystem=strict), an empty /tmp (PrivateTmp=), /home
#     and /root empty (ProtectHome=), a /proc of the process's own entries (ProcSubset=pid,
#     ProtectProc=invisible). A scheduler and a worker that registers with it render a job
#     submitted with the admin token, bit-identical to `farm render`; SIGTERM stops both with
#     exit 0. Under strace (when installed), every system call both processes and the scheduler's
#     `farm check-scene` children made must pass the unit's SystemCallFilter= (expanded by
#     systemd-analyze syscall-filter), every socket the RestrictAddressFamilies=, no mapping be
#     writable and executable (MemoryDenyWriteExecute=), no device but the basic ones be opened
#     (PrivateDevices=), and no file be written outside the service's folders and /tmp.
# Skips (77) without systemd-analyze; without root (setpriv, mount namespaces), part 3 is left out
# with a note.
set -u
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"

require_tool systemd-analyze
farm=$FARM_BINARY
[ -x "$farm" ] || fail "no farm binary at $farm"
python=${FARM_TEST_PYTHON:-/usr/bin/python3}
[ -x "$python" ] || python=/usr/bin/python3
units=$FARM_SOURCE_DIR/deploy/systemd
for f in farm-scheduler.service farm-worker@.service renderfarm.default; do
  [ -r "$units/$f" ] || fail "$units/$f is missing"
done

# Not under /tmp, of which the services get a private one.
tmp=$(mktemp -d /var/tmp/farm-systemd-test.XXXXXX)
chmod 755 "$tmp"
# The units run the .deb's /usr/bin/farm; here a copy of the build's, where their sandbox still
# shows it (a build under /tmp, /home or /root is hidden by PrivateTmp= and ProtectHome=).
mkdir -p "$tmp/bin" && cp "$FARM_BINARY" "$tmp/bin/farm" && chmod 755 "$tmp/bin" "$tmp/bin/farm"
farm="$tmp/bin/farm"
pids=()
cleanup() {
  local pid i
  for pid in "${pids[@]}"; do
    # The farm first: strace, told to stop, would leave its tracee running.
    pkill -TERM -P "$pid" 2>/dev/null
    kill -TERM "$pid" 2>/dev/null
    for i in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  rm -rf "$tmp"
}
trap cleanup EXIT

# --- 1. systemd-analyze verify
mkdir -p "$tmp/units/farm-scheduler.service.d"
for unit in farm-scheduler.service farm-worker@.service; do
  grep -q '^ExecStart=/usr/bin/farm ' "$units/$unit" || fail "$unit: ExecStart does not run /usr/bin/farm (the .deb's)"
  sed "s#^ExecStart=/usr/bin/farm #ExecStart=$farm #" "$units/$unit" >"$tmp/units/$unit"
done
verify() {  # verify UNIT: fails on a non-zero exit or on anything said
  local said
  said=$(cd "$tmp/units" && systemd-analyze verify --man=no "$1" 2>&1)
  local rc=$?
  if [ $rc -ne 0 ] || [ -n "$said" ]; then
    echo "$said" >&2
    fail "systemd-analyze verify $1: exit $rc${said:+, and it said the above}"
  fi
  echo "systemd-analyze verify $1: clean"
}
verify farm-scheduler.service
verify farm-worker@.service
verify farm-worker@50052.service
cp "$units/farm-scheduler.service.d/postgresql-password.conf.example" \
  "$tmp/units/farm-scheduler.service.d/postgresql-password.conf"
verify farm-scheduler.service
# The canary: the same check must catch a bad value, here and in the drop-in.
sed -i 's/^ProtectSystem=strict$/ProtectSystem=strictt/' "$tmp/units/farm-scheduler.service"
said=$(cd "$tmp/units" && systemd-analyze verify --man=no farm-scheduler.service 2>&1)
grep -q strictt <<<"$said" || fail "systemd-analyze verify did not report ProtectSystem=strictt: the check cannot fail"
sed -i 's/^ProtectSystem=strictt$/ProtectSystem=strict/' "$tmp/units/farm-scheduler.service"
echo 'PrivateTmp=perhaps' >>"$tmp/units/farm-scheduler.service.d/postgresql-password.conf"
said=$(cd "$tmp/units" && systemd-analyze verify --man=no farm-scheduler.service 2>&1)
grep -q perhaps <<<"$said" || fail "systemd-analyze verify did not read the drop-in folder: the drop-in check proves nothing"
rm "$tmp/units/farm-scheduler.service.d/postgresql-password.conf"
echo "systemd-analyze verify reports a bad value in a unit and in its drop-in (checked on broken copies)"

# --- 2. systemd-analyze security
for unit in farm-scheduler.service farm-worker@50052.service; do
  said=$(cd "$tmp/units" && systemd-analyze security --offline=yes "$unit" 2>&1)
  level=$(grep -o 'Overall exposure level for [^:]*: [0-9.]* [A-Z]*' <<<"$said")
  [ -n "$level" ] || { echo "$said" >&2; fail "systemd-analyze security --offline=yes $unit gave no exposure level"; }
  echo "$level"
  score=$(awk '{print $(NF-1)}' <<<"$level")
  awk -v s="$score" 'BEGIN { exit !(s < 5.0) }' || fail "$unit: exposure $score, MEDIUM or worse"
done

# --- 3. The command lines, run as the services would run them
if [ "$(id -u)" -ne 0 ]; then
  echo "note: not root: the units' command lines are not run (setpriv and mount namespaces need root)"
  echo "PASS"
  exit 0
fi
free_port() {
  "$python" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
scheduler_port=$(free_port)
worker_port=$(free_port)
FARM="$farm" sh "$FARM_SOURCE_DIR/deploy/compose/make-secrets.sh" "$tmp/secrets" >/dev/null ||
  fail "make-secrets.sh could not make the credentials"
service_uid=65534 service_gid=65534  # nobody: a user that owns nothing, as a DynamicUser

# The site's settings: renderfarm.default as shipped (every line a comment), then this test's.
cp "$units/renderfarm.default" "$tmp/renderfarm.default"
cat >>"$tmp/renderfarm.default" <<EOF
FARM_SCHEDULER_LISTEN=127.0.0.1:$scheduler_port
FARM_WORKER_SCHEDULERS=127.0.0.1:$scheduler_port
FARM_WORKER_HOST=127.0.0.1
FARM_WORKER_THREADS=2
EOF

# The file-system side of a unit's hardening, in the mount namespace `unshare --mount` made:
# sandbox.sh COMMAND..., SANDBOX_RW naming the folders that stay writable.
cat >"$tmp/sandbox.sh" <<'SANDBOX'
#!/bin/sh
set -e
for dir in $SANDBOX_RW; do mount --bind "$dir" "$dir"; done
mount -t tmpfs -o mode=1777,nosuid,nodev tmpfs /tmp       # PrivateTmp=yes
mount -t proc -o subset=pid,hidepid=invisible proc /proc  # ProcSubset=pid, ProtectProc=invisible
for dir in /home /root /run/user; do                      # ProtectHome=yes
  if [ -d "$dir" ]; then mount -t tmpfs -o ro,mode=000 tmpfs "$dir"; fi
done
findmnt -rn -o TARGET | while read -r target; do          # ProtectSystem=strict
  case " $SANDBOX_RW " in *" $target "*) continue ;; esac
  case "$target" in /proc | /proc/* | /dev | /dev/* | /tmp) continue ;; esac
  mount -o remount,bind,ro "$target" 2>/dev/null || true
done
# The emulation holds, or the test would prove nothing.
if touch /etc/.farm-sandbox-probe 2>/dev/null || touch "$(dirname "${SANDBOX_RW%% *}")/.farm-sandbox-probe" 2>/dev/null; then
  echo "sandbox.sh: the file system stayed writable" >&2
  exit 3
fi
exec "$@"
SANDBOX
chmod 755 "$tmp/sandbox.sh"
mkdir -p "$tmp/logs"

# unit_values UNIT KEY: every value of KEY= in the unit, one a line.
unit_values() {
  sed -n "s/^$2=//p" "$units/$1"
}

# start_unit UNIT INSTANCE LOG: runs the unit's ExecStart as systemd would; sets started_pid.
start_unit() {
  local unit=$1 instance=$2 log=$3
  local name=${unit%.service}
  local creds=$tmp/creds/$name state=$tmp/state cache=$tmp/cache
  mkdir -p "$creds" "$state" "$cache"
  # LoadCredential=ID:PATH: the file make-secrets.sh makes under PATH's name, as ID, the
  # service's alone (systemd gives it mode 0400 in a folder of its own).
  local credential id path
  while read -r credential; do
    id=${credential%%:*}
    path=${credential#*:}
    [ -r "$tmp/secrets/$(basename "$path")" ] ||
      fail "$unit: LoadCredential=$credential names a file make-secrets.sh does not make"
    install -m 0400 -o $service_uid -g $service_gid "$tmp/secrets/$(basename "$path")" "$creds/$id"
  done < <(unit_values "$unit" LoadCredential)
  chown $service_uid:$service_gid "$creds" && chmod 0500 "$creds"
  local dir writable=$tmp/logs
  for dir in $(unit_values "$unit" StateDirectory); do
    install -d -m 0750 -o $service_uid -g $service_gid "$state/$dir"
    writable="$state/$dir $writable"
  done
  for dir in $(unit_values "$unit" CacheDirectory); do
    dir=${dir//%i/$instance}
    install -d -m 0750 -o $service_uid -g $service_gid "$cache/$dir"
    writable="$cache/$dir $writable"
  done
  local line
  line=$(unit_values "$unit" ExecStart)
  line=${line//%S/$state}
  line=${line//%C/$cache}
  line=${line//%d/$creds}
  line=${line//%i/$instance}
  line=${line/#\/usr\/bin\/farm /$farm }
  local umask_value
  umask_value=$(unit_values "$unit" UMask)
  (
    # Environment=, then EnvironmentFile= (which overrides it), then the command line's variables.
    while read -r assignment; do eval "export $assignment"; done < <(unit_values "$unit" Environment)
    set -a
    source "$tmp/renderfarm.default"
    set +a
    set +u  # as systemd: an unset variable is empty
    eval "set -- $line"
    cd /
    umask "${umask_value:-0022}"
    tracer=()
    if command -v strace >/dev/null; then
      tracer=(strace -f -y -qq -o "$tmp/logs/$(basename "$log").strace" --)
    fi
    export SANDBOX_RW=$writable
    exec unshare --mount --propagation private -- "$tmp/sandbox.sh" \
      "${tracer[@]}" setpriv --reuid=$service_uid --regid=$service_gid --clear-groups -- "$@"
  ) >"$log" 2>&1 &
  started_pid=$!
  pids+=("$started_pid")
}

# wait_for LOG TEXT PID: until LOG says TEXT (60 s), or the process ended.
wait_for() {
  local i
  for i in $(seq 1 300); do
    grep -q "$2" "$1" 2>/dev/null && return 0
    kill -0 "$3" 2>/dev/null || { cat "$1" >&2; fail "it ended before saying '$2'"; }
    sleep 0.2
  done
  cat "$1" >&2
  fail "no '$2' in $1 after 60 s"
}

start_unit farm-scheduler.service "" "$tmp/scheduler.log"
scheduler_pid=$started_pid
wait_for "$tmp/scheduler.log" "scheduler listening on 127.0.0.1:$scheduler_port" $scheduler_pid
start_unit farm-worker@.service "$worker_port" "$tmp/worker.log"
worker_pid=$started_pid
wait_for "$tmp/worker.log" "registered with the scheduler" $worker_pid
echo "the units' command lines: a scheduler on :$scheduler_port and a worker on :$worker_port registered with it"

# Jobs that take every path through the farm, so that the calls of each are seen: the raster
# engine's cornell; the ray engine's whitted with an Embree check at the merge (Embree's and TBB's
# threads in the scheduler); and 4 frames of the turntable with their video, which the scheduler
# makes with ffmpeg (a child under the same hardening), when ffmpeg is installed.
mkdir -p "$tmp/client" "$tmp/job/assets"
cp "$FARM_SOURCE_DIR"/jobs/assets/{cornell_box.obj,cornell_box.mtl,sphere.obj,torus.gltf} "$tmp/job/assets/"
"$python" - "$FARM_SOURCE_DIR/jobs" "$tmp/job" <<'JOB' || fail "cannot write the test's jobs"
import json, sys
source, target = sys.argv[1:]
job = json.load(open(f"{source}/whitted.json"))
job["validate"] = {"embree_rays": 4096}
json.dump(job, open(f"{target}/whitted.json", "w"))
job = json.load(open(f"{source}/turntable.json"))
job["frames"]["end"] = 4
json.dump(job, open(f"{target}/turntable.json", "w"))
JOB
jobs=("$FARM_SOURCE_DIR/jobs/cornell.json" "$tmp/job/whitted.json")
if command -v ffmpeg >/dev/null; then
  jobs+=("$tmp/job/turntable.json")
else
  echo "note: ffmpeg is not installed: no video job (the scheduler's ffmpeg child is not exercised)"
fi
for job in "${jobs[@]}"; do
  name=$(basename "$job" .json)
  (cd "$tmp/client" && timeout 300 "$farm" submit "$job" --width 64 --height 64 \
    --scheduler "127.0.0.1:$scheduler_port" --token-file "$tmp/secrets/admin.token" --wait) \
    >"$tmp/submit.log" 2>&1 || { cat "$tmp/submit.log" "$tmp/scheduler.log" >&2; fail "$name did not succeed"; }
  result=$tmp/client/out/$name.exr
  if [ "$name" = turntable ]; then
    result=$tmp/client/out/turntable/turntable.0001.exr
    "$farm" render "$job" --width 64 --height 64 --out "$tmp/$name-reference.####.exr" --preview none \
      --video none --quiet >/dev/null 2>&1 || fail "farm render $name failed"
    set -- "$tmp/$name-reference.0001.exr"
    [ -s "$tmp/client/out/turntable.mp4" ] || fail "the turntable's video did not come back"
  else
    "$farm" render "$job" --width 64 --height 64 --out "$tmp/$name-reference.exr" --preview none --quiet \
      >/dev/null 2>&1 || fail "farm render $name failed"
    set -- "$tmp/$name-reference.exr"
  fi
  "$farm" compare "$1" "$result" --metric exact >/dev/null || fail "$name: the EXR differs from farm render's"
done
echo "${#jobs[@]} jobs rendered through them (cornell, whitted with an Embree check, a turntable with its video) are bit-identical to farm render"

# SIGTERM, as systemctl stop sends it (to the farm itself, under strace and setpriv's exec).
for pid_var in worker_pid scheduler_pid; do
  pid=${!pid_var}
  farm_pid=$pid
  if command -v strace >/dev/null; then
    farm_pid=$(pgrep -P "$pid" | head -n 1)
  fi
  kill -TERM "$farm_pid"
  wait "$pid"
  rc=$?
  [ $rc -eq 0 ] || { cat "$tmp/${pid_var%_pid}.log" >&2; fail "${pid_var%_pid}: exit $rc after SIGTERM"; }
done
pids=()
echo "SIGTERM stopped both, exit 0"

if ! command -v strace >/dev/null; then
  echo "note: strace is not installed: the system calls were not checked against the units' filters"
  echo "PASS"
  exit 0
fi

# The system calls, against each unit's own filters.
for unit in farm-scheduler.service:scheduler farm-worker@.service:worker; do
  "$python" - "$units/${unit%%:*}" "$tmp/logs/${unit##*:}.log.strace" "$farm" "$tmp/state" "$tmp/cache" <<'EOF' ||
import re, subprocess, sys

unit_path, log_path, farm, state, cache = sys.argv[1:]
values = {}
for line in open(unit_path):
    if "=" in line and not line.startswith("#"):
        key, value = line.rstrip("\n").split("=", 1)
        values.setdefault(key, []).append(value)

groups = {}
def expand(name):
    if not name.startswith("@"):
        return {name}
    if name not in groups:
        out = subprocess.run(["systemd-analyze", "syscall-filter", name], capture_output=True, text=True, check=True)
        names = set()
        for word in out.stdout.splitlines()[1:]:
            word = word.strip()
            if word and not word.startswith("#"):
                names |= expand(word)
        groups[name] = names
    return groups[name]

allowed = set()
for value in values.get("SystemCallFilter", []):
    if value.startswith("~"):
        for name in value[1:].split():
            allowed -= expand(name)
    else:
        for name in value.split():
            allowed |= expand(name)
families = set(" ".join(values.get("RestrictAddressFamilies", [])).split())
no_wx = values.get("MemoryDenyWriteExecute", ["no"])[-1] == "yes"
writable = (state + "/", cache + "/", "/tmp/", "/dev/null")
# What PrivateDevices= leaves in /dev.
devices = ("/dev/null", "/dev/zero", "/dev/full", "/dev/random", "/dev/urandom", "/dev/tty", "/dev/ptmx",
           "/dev/pts/", "/dev/shm/", "/dev/stdin", "/dev/stdout", "/dev/stderr", "/dev/fd/")

problems, used, pids = [], set(), set()
first_pid, farm_started = None, False
call = re.compile(r"^(\d+) +(?:<\.\.\. )?(\w+)(?:\(| resumed>)")
for line in open(log_path):
    m = call.match(line)
    if not m:
        continue
    pid, name = m.groups()
    first_pid = first_pid or pid
    # Until it executes the farm, the first process is setpriv becoming the service's user;
    # every other process is a thread or a child of the farm.
    if pid == first_pid and not farm_started:
        farm_started = bool(re.match(rf'{pid} +execve\("{re.escape(farm)}"', line)) and line.rstrip().endswith("= 0")
        if not farm_started:
            continue
    pids.add(pid)
    used.add(name)
    if name in ("socket", "socketpair"):
        family = re.search(r"\((AF_\w+)", line)
        if family and families and family.group(1) not in families:
            problems.append(f"a socket of {family.group(1)}, outside RestrictAddressFamilies: {line.strip()}")
    if no_wx and ((name == "mmap" and "PROT_WRITE" in line and "PROT_EXEC" in line)
                  or (name in ("mprotect", "pkey_mprotect") and "PROT_EXEC" in line)):
        problems.append(f"writable and executable memory, which MemoryDenyWriteExecute forbids: {line.strip()}")
    opened = re.match(r'\d+ +open(?:at)?\((?:AT_FDCWD<[^>]*>, )?"(/dev/[^"]*)"', line)
    if opened and not opened.group(1).startswith(devices):
        problems.append(f"a device PrivateDevices= hides: {line.strip()}")
    written = None
    if name in ("open", "openat", "creat") and re.search(r"O_WRONLY|O_RDWR|O_CREAT", line):
        written = line
    elif name in ("mkdir", "mkdirat", "rename", "renameat", "renameat2", "unlink", "unlinkat", "link", "linkat",
                  "symlink", "symlinkat", "rmdir", "truncate"):
        written = line
    if written and "= -1" not in written:
        paths = re.findall(r'(?:\d+<([^>]*)>, )?"([^"]*)"', written)
        for folder, path in paths:
            full = path if path.startswith("/") else (folder + "/" + path if folder else "/" + path)
            if not full.startswith(writable):
                problems.append(f"a write outside the state, cache and temporary folders (ProtectSystem=strict): {written.strip()}")
if not farm_started:
    problems.append("the log shows no exec of the farm")
denied = sorted(used - allowed)
if denied:
    problems.append(f"system calls outside SystemCallFilter= (they would fail with EPERM): {', '.join(denied)}")
print(f"{unit_path.rsplit('/', 1)[1]}: {len(used)} distinct system calls in {len(pids)} processes and threads, "
      f"{len(denied)} outside its SystemCallFilter= ({len(allowed)} allowed); {len(problems)} problem(s)")
for p in problems[:20]:
    print("  " + p, file=sys.stderr)
sys.exit(1 if problems else 0)
EOF
    fail "${unit%%:*}: its hardening forbids something the farm did (above)"
done
echo "PASS"
