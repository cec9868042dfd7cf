#!/usr/bin/env bash
# deploy/slurm/enavi-farm.sbatch on a real one-node Slurm cluster: Debian's munged, slurmctld and
# slurmd, configured here in a temporary directory (own slurm.conf, state, spool, munge key and
# socket, ports unused by the system's daemons) on loopback, and stopped and removed afterwards,
# also on failure. Installs nothing. Needs root (the daemons and the job run as root); exits 77
# (ctest: skipped) without root or without the Slurm/munge binaries.
#
#   slurm_one_node_test.sh ENAVI_BINARY FAKE_EPISODE SBATCH_SCRIPT
#
# Cases: (1) 3 worker tasks run a job: every episode has exactly one result in the SQLite database;
# (2) one worker step is cancelled (scancel --signal=TERM JOBID.STEP) while it runs an episode: it
# drains (finishes that episode, takes no new one), the others finish the job, still every result
# exactly once; (3) the whole Slurm job is cancelled midway with a plain `scancel JOBID`: nothing
# stored is lost or doubled, and the script submitted again on the same farm directory (no job
# spec: it serves the database's unfinished jobs), with one worker task of its own and two more
# from the array form, finishes the job, every result exactly once; the array's workers start
# first, with the cancelled farm's server.env still in place, and must wait for the new farm.
set -euo pipefail

enavi=$1 fake_episode=$2 sbatch_script=$3

skip() { echo "SKIPPED: $*"; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "needs root to run munged, slurmctld and slurmd (CI runs as root)"
for tool in munged slurmctld slurmd sbatch srun scontrol squeue scancel sinfo sqlite3; do
  command -v "$tool" >/dev/null || [ -x "/usr/sbin/$tool" ] ||
    skip "$tool not installed (scripts/install-deps.sh installs slurmctld slurmd slurm-client munge)"
done
export PATH=$PATH:/usr/sbin

dir=$(mktemp -d /tmp/enavi-slurm-XXXXXX)
chmod 755 "$dir"
export SLURM_CONF=$dir/slurm.conf
# The farm script puts each worker's work directory under $TMPDIR (on a cluster, the job's
# scratch); the jobs inherit this one, inside the directory cleanup removes.
export TMPDIR=$dir/tmp
mkdir -p "$TMPDIR"
fail() { echo "FAIL: $*" >&2; exit 1; }
# Loops below poll until a deadline in wall seconds (each poll runs a Slurm or sqlite command of
# its own, so counting iterations would not bound the time on a loaded machine).
before() { [ "$SECONDS" -lt "$1" ]; }

cleanup() {
  local rc=$?
  set +e
  # This cluster's jobs only (SLURM_CONF names it), while its controller still runs.
  if [ -s "$dir/slurmctld.pid" ]; then
    scancel --quiet --full "--user=$(id -un)" 2>/dev/null
    local deadline=$((SECONDS + 10))
    while before "$deadline" && [ -n "$(squeue -h 2>/dev/null)" ]; do sleep 0.1; done
  fi
  for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
    [ -s "$pidfile" ] || continue
    pid=$(<"$pidfile")
    kill -TERM "$pid" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null
  done
  # Whatever of ours outlived the daemons (slurmstepd and the job's processes carry our
  # SLURM_CONF in their environment).
  for env in /proc/[0-9]*/environ; do
    grep -qzx "SLURM_CONF=$SLURM_CONF" "$env" 2>/dev/null || continue
    pid=${env#/proc/}
    pid=${pid%/environ}
    [ "$pid" = $$ ] || kill -KILL "$pid" 2>/dev/null
  done
  if [ $rc -ne 0 ] && [ $rc -ne 77 ]; then
    for f in "$dir"/*.log "$dir"/farm*/logs/*.log "$dir"/job-*.out; do
      [ -f "$f" ] && { echo "==== $f"; tail -n 40 "$f"; }
    done
  fi
  if [ "${ENAVI_KEEP_SYSTEM_LOGS:-}" = 1 ]; then echo "kept $dir"; else rm -rf "$dir"; fi
  exit $rc
}
trap cleanup EXIT

# Ports: a pair not bound by anything on this host (the system's Slurm uses 6817/6818).
port=$((20000 + ($$ % 2000) * 2))
while ss -Hltn "( sport = :$port or sport = :$((port + 1)) )" | grep -q .; do port=$((port + 2)); done
cluster=enavi-slurm-$$

# munge: its own key, socket, pid, log and seed; --force because it runs as root.
dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge.key"
munged --force --key-file="$dir/munge.key" --socket="$dir/munge.socket" \
  --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munged.seed"

# One node, "localhost" on 127.0.0.1, 4 CPUs whatever this machine has (config_overrides), no
# cgroups (proctrack/linuxproc, task/none: the test must run in containers), no accounting.
mkdir -p "$dir/state" "$dir/spool"
cat >"$SLURM_CONF" <<EOF
ClusterName=$cluster
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
MailProg=/bin/true
KillWait=30
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 CPUs=4 RealMemory=1000 State=UNKNOWN
PartitionName=enavi Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -c -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF" -N localhost
deadline=$((SECONDS + 30))
while before "$deadline"; do
  [ "$(sinfo -h -n localhost -o %t 2>/dev/null)" = idle ] && break
  sleep 0.1
done
[ "$(sinfo -h -n localhost -o %t)" = idle ] || fail "the node did not come up: $(sinfo 2>&1)"
echo "one-node cluster $cluster up on ports $port/$((port + 1))"

# Fake episodes (tests/system/fake_episode), the same kind the other system tests use.
cat >"$dir/job.yaml" <<EOF
name: slurm
boards: [tx2, pi4b]
scenarios: [s1]
methods: [baseline, enavi]
seeds: 3
EOF
total=12

job_state() { scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p'; }

# Submits the farm script with 3 worker tasks; prints the Slurm job id.
submit() {
  local farm=$1 sleep_s=$2
  shift 2
  mkdir -p "$farm"
  ENAVI_BIN=$enavi ENAVI_FARM_DIR=$farm ENAVI_INTERFACE=127.0.0.1 \
    ENAVI_EPISODE_CMD=$fake_episode FAKE_EPISODE_SLEEP_S=$sleep_s \
    FAKE_EPISODE_LOG=$farm/episodes.txt ENAVI_DRAIN_TIMEOUT=20 \
    sbatch --parsable --ntasks="${TASKS:-3}" --cpus-per-task=1 --time=5 --chdir="$dir" \
    --output="$dir/job-%j.out" "$sbatch_script" "$@"
}

wait_job() {
  local id=$1 state deadline=$((SECONDS + 120))
  while before "$deadline"; do
    state=$(job_state "$id")
    case $state in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;; esac
    sleep 0.1
  done
  echo "$state"
}

# Results of the farm's database once it has at least $2.
wait_results() {
  local deadline=$((SECONDS + 60))
  while before "$deadline"; do
    [ -f "$1/farm.db" ] &&
      [ "$(sqlite3 "$1/farm.db" "SELECT COUNT(*) FROM results" 2>/dev/null || echo 0)" -ge "$2" ] &&
      return 0
    sleep 0.1
  done
  fail "$1: fewer than $2 results after 60 s"
}

# Every episode of the only job in the database is done with exactly one result, and the
# results cover the matrix.
check_exactly_once() {
  local db=$1/farm.db
  [ -f "$db" ] || fail "no database $db"
  local row
  row=$(sqlite3 "$db" "SELECT (SELECT COUNT(*) FROM jobs WHERE state = 'done'),
    (SELECT COUNT(*) FROM episodes WHERE state = 'done'), (SELECT COUNT(*) FROM results),
    (SELECT COUNT(DISTINCT episode_id) FROM results),
    (SELECT COUNT(*) FROM (SELECT DISTINCT board, method, seed FROM results)),
    (SELECT COUNT(*) FROM episodes e LEFT JOIN results r ON r.episode_id = e.id
       WHERE r.episode_id IS NULL)")
  [ "$row" = "1|$total|$total|$total|$total|0" ] ||
    fail "database $db: jobs done|episodes done|results|distinct episodes|distinct cells|episodes without result = $row, want 1|$total|$total|$total|$total|0"
}

# Case 1: the job runs to completion on 3 worker steps and the batch script ends by itself.
id=$(submit "$dir/farm1" 0.5 "$dir/job.yaml")
state=$(wait_job "$id")
[ "$state" = COMPLETED ] || fail "case 1: Slurm job $id ended $state"
check_exactly_once "$dir/farm1"
workers=$(sqlite3 "$dir/farm1/farm.db" "SELECT COUNT(DISTINCT worker) FROM results")
[ "$workers" -ge 2 ] || fail "case 1: only $workers worker step(s) ran episodes"
grep -q "server http://127.0.0.1:" "$dir/job-$id.out" || fail "case 1: no server line in the job output"
echo "case 1: $total results exactly once from $workers worker steps"

# Case 2: episodes of 2 s; once the first results are in, one worker step is cancelled while it
# runs an episode. It must drain: finish that episode (its result stored), then leave.
id=$(submit "$dir/farm2" 2 "$dir/job.yaml")
wait_results "$dir/farm2" 1
# The step of task 1 (worker SLURMJOB-t1) while it holds a lease.
victim="$id-t1"
running=
deadline=$((SECONDS + 10))
while before "$deadline"; do
  running=$(sqlite3 "$dir/farm2/farm.db" \
    "SELECT id FROM episodes WHERE state = 'leased' AND lease_owner = '$victim' LIMIT 1" 2>/dev/null || true)
  [ -n "$running" ] && break
  sleep 0.1
done
[ -n "$running" ] || fail "case 2: worker $victim never held a lease"
step=$(squeue -h -s -j "$id" -o "%i %j" | awk '$2 == "enavi-worker-t1" {print $1}')
[ -n "$step" ] || fail "case 2: no job step enavi-worker-t1: $(squeue -s -j "$id" -o '%i %j')"
scancel --signal=TERM "$step"
echo "case 2: cancelled step $step ($victim) while it ran episode $running"
state=$(wait_job "$id")
[ "$state" = COMPLETED ] || fail "case 2: Slurm job $id ended $state"
check_exactly_once "$dir/farm2"
grep -q "draining" "$dir/farm2/logs/worker-$id-t1.log" || fail "case 2: $victim did not drain"
grep -q "stopped" "$dir/farm2/logs/worker-$id-t1.log" || fail "case 2: $victim did not stop cleanly"
owner=$(sqlite3 "$dir/farm2/farm.db" "SELECT worker FROM results WHERE episode_id = '$running'")
[ "$owner" = "$victim" ] || fail "case 2: episode $running, running when $victim was cancelled, has its result from '$owner'"
remaining=$(sqlite3 "$dir/farm2/farm.db" "SELECT COUNT(*) FROM results WHERE worker != '$victim'")
echo "case 2: $total results exactly once; $victim finished $running, the others $remaining episodes"

# Case 3: a plain scancel of the whole Slurm job while episodes run, then the script again.
id=$(submit "$dir/farm3" 2 "$dir/job.yaml")
wait_results "$dir/farm3" 2
scancel "$id"
state=$(wait_job "$id")
[ "$state" = CANCELLED ] || fail "case 3: Slurm job $id ended $state after scancel"
row=$(sqlite3 "$dir/farm3/farm.db" "SELECT (SELECT COUNT(*) FROM results),
  (SELECT COUNT(DISTINCT episode_id) FROM results), (SELECT COUNT(*) FROM episodes WHERE state = 'failed'),
  (SELECT COUNT(*) FROM jobs WHERE state = 'running')")
IFS='|' read -r stored distinct failed running <<<"$row"
[ "$stored" = "$distinct" ] && [ "$failed" = 0 ] && [ "$running" = 1 ] ||
  fail "case 3: after scancel: results|distinct|failed episodes|running jobs = $row"
[ "$stored" -lt "$total" ] || fail "case 3: the job finished before the scancel; nothing was tested"
echo "case 3: scancel $id with $stored/$total results stored; submitting the farm again"
# A farm job killed before its clean-up leaves its server.env behind. Plant one naming the
# cancelled job (whether this one was left depends on how fast Slurm killed the batch shell) and
# start the array form first: its workers must wait for the new farm job, not join the dead one.
{
  echo "export ENAVI_SERVER_HOST=localhost"
  echo "export ENAVI_DOMAIN=$((id % 233))"
  echo "export ENAVI_PARTITION=slurm-$id"
  echo "export ENAVI_SERVER=http://127.0.0.1:9"
  echo "export ENAVI_FARM_JOB=$id"
} >"$dir/farm3/server.env"
array=$(ENAVI_BIN=$enavi ENAVI_FARM_DIR=$dir/farm3 ENAVI_INTERFACE=127.0.0.1 \
  ENAVI_EPISODE_CMD=$fake_episode FAKE_EPISODE_SLEEP_S=2 ENAVI_DRAIN_TIMEOUT=20 \
  sbatch --parsable --array=1-2 --ntasks=1 --cpus-per-task=1 --time=5 --chdir="$dir" \
  --output="$dir/array-%A_%a.out" "$sbatch_script")
deadline=$((SECONDS + 60))
until [ "$(squeue -h -j "$array" -t RUNNING -o %i | wc -l)" -ge 2 ]; do
  before "$deadline" || fail "case 3: the array tasks did not start"
  sleep 0.2
done
sleep 2  # both have read the stale file by now
id=$(TASKS=1 submit "$dir/farm3" 2)
deadline=$((SECONDS + 120))
while before "$deadline"; do
  [ "$(sqlite3 "$dir/farm3/farm.db" "SELECT state FROM jobs" 2>/dev/null)" = "done" ] && break
  sleep 0.1
done
scancel --signal=TERM "$array" "$id"
state=$(wait_job "$id")
[ "$state" = COMPLETED ] || fail "case 3: the resuming Slurm job $id ended $state"
for task in 1 2; do
  state=$(wait_job "${array}_$task")
  [ "$state" = COMPLETED ] || fail "case 3: array task ${array}_$task ended $state"
done
check_exactly_once "$dir/farm3"
by_array=$(sqlite3 "$dir/farm3/farm.db" "SELECT COUNT(*) FROM results WHERE worker LIKE '$array-a%'")
[ "$by_array" -ge 1 ] || fail "case 3: the array form's workers ran no episode"
echo "case 3: $total results exactly once after the cancelled farm was submitted again" \
  "($by_array by the array form's workers)"
