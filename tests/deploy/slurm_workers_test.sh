#!/bin/bash
# Deploy.slurm_workers: deploy/slurm/farm-workers.sbatch on a real one-node Slurm cluster.
#
# Brings up munged, slurmctld and slurmd (Debian's slurm-wlm and munge) with their config, key,
# sockets, state and logs in a temporary folder, and a `farm scheduler` with tokens on a free
# port; submits the array with two tasks of one CPU each, as a user would, and checks that:
#   - both tasks run and their workers register with the CPUs Slurm gave them (1 thread each);
#   - a job rendered through the scheduler by both workers is bit-identical to `farm render`;
#   - `scancel` of one task while a second job renders: its worker leaves (SIGTERM, exit 0), its
#     units go to the other worker, and that job is still bit-identical to `farm render`;
#   - SIGTERM to the other task's batch shell alone (what `--signal=B:TERM@60` sends before the
#     time limit) makes its worker leave and the job end COMPLETED with exit code 0;
#   - a one-minute task gets that SIGTERM from the script's own #SBATCH --signal and ends the same.
# Skips (77) without root, the Slurm or munge programs, or when slurmd cannot start here. Every
# daemon, job and file it made is gone at the end, failed or not.
set -u
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"

require_root "the Slurm test (slurmd starts jobs as any user, munged's key is root's)"
for tool in munged mungekey munge unmunge slurmctld slurmd sbatch squeue scancel scontrol sinfo; do
  require_tool "$tool"
done
python=/usr/bin/python3
[ -x "$python" ] || skip "python3 is not installed (the test reads the farm's JSON with it)"

farm=$FARM_BINARY
sbatch_script=$FARM_SOURCE_DIR/deploy/slurm/farm-workers.sbatch
[ -r "$sbatch_script" ] || fail "$sbatch_script is missing"
started=$(date +%s)

tmp=$(mktemp -d /tmp/farm-slurm-test.XXXXXX)
chmod 755 "$tmp"  # munged wants every folder above its socket searchable by all
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log" "$tmp/out" "$tmp/job/assets"
export SLURM_CONF=$tmp/slurm.conf  # for sbatch, squeue, scancel, scontrol, sinfo and the daemons

munged_pid= slurmctld_pid= slurmd_pid= scheduler_pid=

# The end of a process this test started: SIGTERM, up to 10 s, then SIGKILL.
stop_pid() {
  local pid=$1 i
  [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 0
  kill -TERM "$pid" 2>/dev/null
  for i in $(seq 100); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  return 0
}

# Processes left by this test's Slurm: slurmstepd and the jobs' processes (the workers) outlive
# slurmd. They are known by the SLURM_CONF this test gave them (slurmd passes it on to
# slurmstepd, and sbatch exports it to the jobs), so nothing else on the machine is touched.
leftovers() {
  local dir env
  for dir in /proc/[0-9]*; do
    [ "${dir#/proc/}" = $$ ] && continue
    env=$(tr '\0' '\n' 2>/dev/null <"$dir/environ") || continue
    grep -qxF "SLURM_CONF=$SLURM_CONF" <<<"$env" || continue
    if grep -q '^SLURM_JOB_ID=' <<<"$env" || [ "$(cat "$dir/comm" 2>/dev/null)" = slurmstepd ]; then
      echo "${dir#/proc/}"
    fi
  done
}

cleanup() {
  local status=$? i pids
  trap - EXIT
  if [ -n "$slurmctld_pid" ] && kill -0 "$slurmctld_pid" 2>/dev/null; then
    scancel --user=root >/dev/null 2>&1  # every job of this cluster (it is the test's own)
    for i in $(seq 100); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  stop_pid "$slurmd_pid"
  stop_pid "$slurmctld_pid"
  # A slurmstepd may still be finishing its job for a moment after squeue has let it go.
  for i in $(seq 50); do
    pids=$(leftovers)
    [ -z "$pids" ] && break
    if [ "$i" -eq 25 ]; then
      echo "slurm_workers: killing leftover processes $pids"
      kill -KILL $pids 2>/dev/null
    fi
    sleep 0.2
  done
  stop_pid "$scheduler_pid"
  stop_pid "$munged_pid"
  rm -rf "$tmp"
  echo "slurm_workers: $(($(date +%s) - started)) s"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# The last lines of every log, for a failure message.
logs() {
  local f
  for f in "$tmp"/log/* "$tmp"/out/*; do
    [ -s "$f" ] || continue
    echo "--- ${f#"$tmp"/}"
    tail -n 15 "$f"
  done
}
die() {
  fail "$*
$(logs)"
}

# Free TCP ports from the kernel (bound to port 0, then released).
free_ports() {
  "$python" - "$1" <<'EOF'
import socket, sys
held = [socket.socket() for _ in range(int(sys.argv[1]))]
for s in held:
    s.bind(("", 0))
print(" ".join(str(s.getsockname()[1]) for s in held))
EOF
}

# until_true SECONDS WHAT COMMAND...: polls COMMAND every 0.25 s until it succeeds, or fails the
# test after SECONDS.
until_true() {
  local seconds=$1 what=$2
  local deadline=$(($(date +%s) + seconds))
  shift 2
  until "$@"; do
    [ "$(date +%s)" -lt "$deadline" ] || die "timed out after $seconds s waiting for $what"
    sleep 0.25
  done
}

# --- munge: its own key, socket and files -------------------------------------------------------
mungekey --create --keyfile="$tmp/munge/munge.key" >/dev/null 2>&1 || fail "mungekey could not make a key"
munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" \
  --seed-file="$tmp/munge/munged.seed" >"$tmp/log/munged.log" 2>&1 &
munged_pid=$!
munge_works() { munge -n -S "$tmp/munge/socket" 2>/dev/null | unmunge -S "$tmp/munge/socket" >/dev/null 2>&1; }
deadline=$(($(date +%s) + 30))
until munge_works; do
  kill -0 "$munged_pid" 2>/dev/null || skip "munged cannot start here: $(tail -n 3 "$tmp/log/munged.log" | tr '\n' ' ')"
  [ "$(date +%s)" -lt "$deadline" ] || die "munged did not answer on its socket within 30 s"
  sleep 0.2
done

# --- Slurm: one node of 2 CPUs, no cgroups (linuxproc tracks a job's processes), no accounting --
node=$(hostname -s)
read -r ctld_port slurmd_port <<<"$(free_ports 2)"
cat >"$SLURM_CONF" <<EOF
ClusterName=farmtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
ReturnToService=2
# The node has 2 CPUs whatever this machine has.
SlurmdParameters=config_overrides
# Ended jobs stay visible to scontrol for 10 minutes (there is no slurmdbd for sacct).
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=30 State=UP
EOF
slurmctld -D -f "$SLURM_CONF" >"$tmp/log/slurmctld.out" 2>&1 &
slurmctld_pid=$!
slurmd -D -f "$SLURM_CONF" -N "$node" >"$tmp/log/slurmd.out" 2>&1 &
slurmd_pid=$!
node_idle() { [ "$(sinfo -h -n "$node" -o %T 2>/dev/null)" = idle ]; }
deadline=$(($(date +%s) + 90))
until node_idle; do
  kill -0 "$slurmd_pid" 2>/dev/null ||
    skip "slurmd cannot start here: $(tail -n 5 "$tmp/log/slurmd.out" "$tmp/log/slurmd.log" 2>/dev/null | tr '\n' ' ')"
  kill -0 "$slurmctld_pid" 2>/dev/null || die "slurmctld exited"
  [ "$(date +%s)" -lt "$deadline" ] || die "the node did not become idle within 90 s: $(sinfo -N 2>&1)"
  sleep 0.5
done
echo "slurm: node $node idle (slurmctld :$ctld_port, slurmd :$slurmd_port)"

# --- the farm: tokens as a real farm would have them, a scheduler on a free port ---------------
# admin: the test's client commands; worker: the workers' token for the scheduler; scheduler:
# the scheduler's token for calling the workers, the only one the workers accept.
for who in admin:admin worker:worker scheduler:scheduler; do
  "$farm" token "${who%%:*}" --roles "${who#*:}" >"$tmp/${who%%:*}.token" 2>"$tmp/${who%%:*}.line" ||
    fail "farm token failed: $(cat "$tmp/${who%%:*}.line")"
done
tail -n 1 "$tmp/admin.line" >"$tmp/scheduler.tokens"
tail -n 1 "$tmp/worker.line" >>"$tmp/scheduler.tokens"
tail -n 1 "$tmp/scheduler.line" >"$tmp/workers.tokens"
chmod 600 "$tmp"/*.token

# --verify-fraction: every job has at least one unit rendered again on a second worker, so both
# workers render some of the first job however the dispatch falls.
"$farm" scheduler --listen 127.0.0.1:0 --data-dir "$tmp/scheduler" --tokens "$tmp/scheduler.tokens" \
  --token-file "$tmp/scheduler.token" --verify-fraction 0.02 >"$tmp/log/scheduler.log" 2>&1 &
scheduler_pid=$!
scheduler_address() { sed -n 's/^scheduler listening on \([^ ]*\).*/\1/p' "$tmp/log/scheduler.log" 2>/dev/null | head -n 1; }
scheduler_listens() { [ -n "$(scheduler_address)" ]; }
until_true 60 "the scheduler to listen" scheduler_listens
scheduler=$(scheduler_address)
until_true 60 "the scheduler to answer its health check" "$farm" health --scheduler "$scheduler" --timeout 2s
client=(--scheduler "$scheduler" --token-file "$tmp/admin.token")

# --- the array: two tasks of one CPU; the workers listen beyond loopback (as on a cluster) -----
export FARM_SCHEDULER=$scheduler FARM_BIN=$farm FARM_TOKEN_FILE=$tmp/worker.token
export FARM_WORKER_TOKENS=$tmp/workers.tokens FARM_CACHE_DIR=$tmp/worker-cache
# A worker on 0.0.0.0 is known to the scheduler by this machine's name; where that does not
# resolve, loopback stands in.
getent hosts "$(hostname)" >/dev/null 2>&1 || export FARM_WORKER_LISTEN=127.0.0.1:0
array=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --time=10 --chdir="$tmp" \
  --output="$tmp/out/worker-%A_%a.out" "$sbatch_script" 2>"$tmp/log/sbatch.err") ||
  die "sbatch failed: $(cat "$tmp/log/sbatch.err")"
array=${array%%;*}
echo "slurm: submitted array job $array"

both_running() { [ "$(squeue -h -j "$array" -t RUNNING -o %i 2>/dev/null | wc -l)" -eq 2 ]; }
until_true 90 "both array tasks to run" both_running

# The workers as the scheduler lists them, one per line: ADDRESS STATE THREADS UNITS_DONE IN_FLIGHT.
workers() {
  "$farm" workers --json "${client[@]}" 2>/dev/null | "$python" -c '
import json, sys
for w in json.load(sys.stdin):
    print(w["address"], w["state"], w["threads"], w["units_done"], len(w.get("current", [])))'
}
both_up() { [ "$(workers | awk '$2 == "WORKER_STATE_UP"' | wc -l)" -eq 2 ]; }
until_true 90 "both workers to register" both_up
while read -r address state threads done_ in_flight; do
  [ "$threads" -eq 1 ] ||
    die "worker $address registered $threads render threads; Slurm gave its task 1 CPU (--cpus-per-task=1)"
done < <(workers)
echo "farm: both workers registered with 1 thread each"

# The port each task's worker listens on, from its own line in the task's output.
worker_port() {
  sed -n 's/^worker listening on .*:\([0-9]*\)$/\1/p' "$tmp/out/worker-${array}_$1.out" 2>/dev/null | head -n 1
}
worker_listens() { [ -n "$(worker_port 1)" ]; }
until_true 30 "task 1's worker to print its address" worker_listens
port1=$(worker_port 1)

# --- a job rendered by both workers, bit-identical to `farm render` ----------------------------
cp "$FARM_SOURCE_DIR/jobs/cornell.json" "$FARM_SOURCE_DIR/jobs/cornell_path.json" "$tmp/job/"
cp "$FARM_SOURCE_DIR"/jobs/assets/cornell_box.* "$tmp/job/assets/"
"$farm" render "$tmp/job/cornell.json" --quiet --threads 1 --out "$tmp/reference.exr" >"$tmp/log/render.log" 2>&1 ||
  die "farm render failed: $(cat "$tmp/log/render.log")"

job=$("$farm" submit "$tmp/job/cornell.json" "${client[@]}" 2>"$tmp/log/submit.err") ||
  die "farm submit failed: $(cat "$tmp/log/submit.err")"
timeout 120 "$farm" watch "$job" "${client[@]}" >"$tmp/log/watch.log" 2>&1 ||
  die "job $job did not succeed: $(tail -n 5 "$tmp/log/watch.log")"
mkdir -p "$tmp/fetched"
"$farm" fetch "$job" -o "$tmp/fetched" "${client[@]}" >"$tmp/log/fetch.log" 2>&1 ||
  die "farm fetch failed: $(cat "$tmp/log/fetch.log")"
"$farm" compare "$tmp/reference.exr" "$tmp/fetched/cornell.exr" --metric exact >"$tmp/log/compare.log" 2>&1 ||
  die "the EXR rendered on the Slurm workers differs from farm render's: $(cat "$tmp/log/compare.log")"
workers >"$tmp/workers.txt"
while read -r address state threads done_ in_flight; do
  [ "$done_" -gt 0 ] || die "worker $address rendered no unit of job $job: $(cat "$tmp/workers.txt")"
done <"$tmp/workers.txt"
echo "farm: job $job rendered by both Slurm workers ($(awk '{print $4}' "$tmp/workers.txt" | paste -sd+) units), bit-identical to farm render"

# --- scancel of task 1 in the middle of a job: its worker leaves, the job ends on task 0 -------
# The path-traced box takes a few seconds of one core, so the cancel comes while units are out.
"$farm" render "$tmp/job/cornell_path.json" --quiet --threads 2 --width 128 --height 128 --spp 256 \
  --out "$tmp/reference_path.exr" >"$tmp/log/render_path.log" 2>&1 ||
  die "farm render failed: $(cat "$tmp/log/render_path.log")"
job2=$("$farm" submit "$tmp/job/cornell_path.json" --width 128 --height 128 --spp 256 "${client[@]}" \
  2>"$tmp/log/submit2.err") || die "farm submit failed: $(cat "$tmp/log/submit2.err")"
task1_busy() { workers | awk -v port=":$port1" '$1 ~ port "$" && $5 > 0' | grep -q .; }
until_true 60 "task 1's worker to get units of job $job2" task1_busy
scancel "${array}_1" || die "scancel ${array}_1 failed"
timeout 180 "$farm" watch "$job2" "${client[@]}" >"$tmp/log/watch2.log" 2>&1 ||
  die "job $job2 did not succeed after task 1 was cancelled: $(tail -n 5 "$tmp/log/watch2.log")"
mkdir -p "$tmp/fetched2"
"$farm" fetch "$job2" -o "$tmp/fetched2" "${client[@]}" >"$tmp/log/fetch2.log" 2>&1 ||
  die "farm fetch failed: $(cat "$tmp/log/fetch2.log")"
"$farm" compare "$tmp/reference_path.exr" "$tmp/fetched2/cornell_path.exr" --metric exact \
  >"$tmp/log/compare2.log" 2>&1 ||
  die "job $job2, finished after a worker left, differs from farm render's: $(cat "$tmp/log/compare2.log")"
echo "farm: job $job2 survived scancel of task 1 mid-render, bit-identical to farm render"

# --- SIGTERM to task 0's batch shell alone, as --signal=B:TERM@60 sends it before the time limit
scancel --batch --signal=TERM "${array}_0" || die "scancel --batch ${array}_0 failed"

job_ended() { [ -z "$(squeue -h -j "$1" -o %i 2>/dev/null)" ]; }
# check_ended JOB OUTPUT STATE: the job ended in STATE with exit code 0:0 (Slurm's record, kept
# MinJobAge), its worker got SIGTERM and the script saw it exit 0 (the task's output). A signal in
# the job's first milliseconds is also a clean end: the script says it stopped the worker before
# it started serving, or did not start it.
check_ended() {
  local job=$1 out=$2 expected=$3 record state code
  if ! grep -q "asked to leave before the worker started" "$out"; then
    grep -q -e "^worker: SIGTERM, shutting down" -e "stopped before it had started serving" "$out" ||
      die "job $job: the worker did not get SIGTERM"
    grep -q "^farm-workers: .* worker exited with status 0$" "$out" ||
      die "job $job: the worker did not exit 0: $(grep 'worker exited' "$out")"
  fi
  record=$(scontrol show job "$job" 2>&1)
  state=$(sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' <<<"$record" | head -n 1)
  code=$(sed -n 's/.* ExitCode=\([0-9:]*\).*/\1/p' <<<"$record" | head -n 1)
  [ "$state" = "$expected" ] && [ "$code" = 0:0 ] ||
    die "job $job ended $state with exit code $code, expected $expected with 0:0"
  echo "slurm: $job $state, exit code $code: $(grep -m1 -e 'worker exited' -e 'before the worker started' "$out")"
}
until_true 90 "task 0 to end" job_ended "${array}_0"
until_true 90 "task 1 to end" job_ended "${array}_1"
# Task 0 was only asked to leave, so it ended on its own; task 1 was cancelled.
check_ended "${array}_0" "$tmp/out/worker-${array}_0.out" COMPLETED
check_ended "${array}_1" "$tmp/out/worker-${array}_1.out" CANCELLED

# --- the time limit: a one-minute task gets the script's own --signal=B:TERM@60 at once (at
# slurmctld's next periodic check, within about 30 s) and ends COMPLETED; without the directive,
# or without the trap, Slurm would end it at the limit as TIMEOUT.
limited=$(sbatch --parsable --array=0 --cpus-per-task=1 --time=1 --chdir="$tmp" \
  --output="$tmp/out/worker-%A_%a.out" "$sbatch_script" 2>"$tmp/log/sbatch.err") ||
  die "sbatch failed: $(cat "$tmp/log/sbatch.err")"
limited=${limited%%;*}
until_true 150 "the one-minute job $limited to end" job_ended "${limited}_0"
grep -q "SIGTERM: asking the worker to leave" "$tmp/out/worker-${limited}_0.out" ||
  die "job ${limited}_0: the script got no SIGTERM before its time limit"
check_ended "${limited}_0" "$tmp/out/worker-${limited}_0.out" COMPLETED
echo "PASS: Slurm array of farm workers rendered bit-identical jobs and left cleanly"
