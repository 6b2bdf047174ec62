#!/usr/bin/env bash
# End-to-end test of `nlvid slurm` on a real Slurm: a single-node cluster
# (munged, slurmctld, slurmd; 2 CPUs) on this machine, started here and
# stopped on exit.
#
#   1. a sharded build of examples/metamodel/hertz-prony.toml as a job array
#      plus the merge job (afterok); the export equals a local
#      `nlvid build` byte for byte;
#   2. the same with slow runs (test_delay) while one array task's nlvid is
#      SIGKILLed mid-run: the task requeues itself, resumes, and the export
#      is still byte-identical;
#   3. an array whose tasks fail: the merge job is cancelled,
#      `nlvid slurm --status` says what to do; doing it completes the build;
#   4. with --bench: wall time of the array build against `nlvid build` on
#      the same runs, and the overhead per task: (a) hertz-prony with runs
#      that sleep (test_delay) (insensitive to other users' load), (b) the CPU-bound
#      membrane study.
#
# Usage (as root: it installs packages and starts slurmd):
#   cargo build --release -p nlvid
#   scripts/slurm-e2e.sh [--bench]
# Environment: NLVID (default target/release/nlvid), E2E_DIR (default
# target/slurm-e2e), BENCH_STUDY (default examples/metamodel/membrane.toml),
# BENCH_TASKS (2), BENCH_REPEAT (3), BENCH_DELAY (400 ms: the sleep of benchmark a),
# BENCH_CPU (1; 0 skips benchmark b), SLURM_PORTS (16817-16818).
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
work=${E2E_DIR:-$repo/target/slurm-e2e}
nlvid=${NLVID:-$repo/target/release/nlvid}
bench=0
[ "${1:-}" = --bench ] && bench=1

say() { printf '\n== %s\n' "$*"; }
die() { printf 'FAIL: %s\n' "$*" >&2; exit 1; }
now() { date +%s.%N; }
secs() { awk "BEGIN {printf \"%.2f\", $2 - $1}"; }

[ "$(id -u)" = 0 ] || die "run as root: the harness installs slurm-wlm and munge and starts slurmd"
[ -x "$nlvid" ] || die "$nlvid missing: run 'cargo build --release -p nlvid' first"

# --- install ------------------------------------------------------------------
if ! command -v slurmctld > /dev/null || ! command -v slurmd > /dev/null \
    || ! command -v sbatch > /dev/null || ! command -v munged > /dev/null; then
    say "installing slurm-wlm and munge (apt-get)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge > /dev/null
fi
slurmctld -V

# --- single-node cluster -----------------------------------------------------
rm -rf "$work"
cluster=$work/cluster
mkdir -p "$cluster"/{munge-key,munge,state,spool,log}
chmod 755 "$cluster" "$cluster/munge"
chmod 700 "$cluster/munge-key"
ports=${SLURM_PORTS:-16817-16818}
host=$(hostname -s)
munged_pid=
poller=
cleanup() {
    local rc=$?
    set +e
    [ -n "$poller" ] && kill "$poller" 2> /dev/null
    if [ -n "${SLURM_CONF:-}" ] && [ -f "$cluster/state/slurmctld.pid" ]; then
        scancel --user=root > /dev/null 2>&1
        for _ in $(seq 30); do [ -z "$(squeue -h 2> /dev/null)" ] && break; sleep 1; done
        scontrol shutdown > /dev/null 2>&1
    fi
    for f in "$cluster/state/slurmd.pid" "$cluster/state/slurmctld.pid"; do
        [ -f "$f" ] || continue
        pid=$(cat "$f")
        for _ in $(seq 20); do kill -0 "$pid" 2> /dev/null || break; sleep 0.5; done
        kill -0 "$pid" 2> /dev/null && kill -KILL "$pid"
    done
    if [ -n "$munged_pid" ]; then
        kill "$munged_pid" 2> /dev/null
        for _ in $(seq 20); do kill -0 "$munged_pid" 2> /dev/null || break; sleep 0.25; done
    fi
    say "daemons stopped"
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

say "starting munged, slurmctld, slurmd ($host, 2 CPUs, ports $ports)"
dd if=/dev/urandom of="$cluster/munge-key/munge.key" bs=128 count=1 status=none
chmod 600 "$cluster/munge-key/munge.key"
munged --force --key-file="$cluster/munge-key/munge.key" --socket="$cluster/munge/munge.sock" \
    --pid-file="$cluster/munge/munged.pid" --log-file="$cluster/log/munged.log" \
    --seed-file="$cluster/munge/munged.seed"
munged_pid=$(cat "$cluster/munge/munged.pid")
# cred_expire: a requeued job may start again cred_expire + 1 s after it
# stopped (Slurm's default 120 s; 5 s keeps the test short).
cat > "$cluster/slurm.conf" << EOF
ClusterName=nlvid-e2e
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=${ports%-*}
SlurmdPort=${ports#*-}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$cluster/munge/munge.sock,cred_expire=5
CredType=cred/munge
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/state/slurmctld.pid
SlurmdPidFile=$cluster/state/slurmd.pid
SlurmctldLogFile=$cluster/log/slurmctld.log
SlurmdLogFile=$cluster/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$cluster/log/jobcomp.txt
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 RealMemory=4096 State=UNKNOWN
PartitionName=e2e Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$cluster/slurm.conf
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
    [ "$(sinfo -h -o %T 2> /dev/null)" = idle ] && break
    sleep 0.5
done
[ "$(sinfo -h -o %T)" = idle ] || die "the node did not come up: see $cluster/log/"
sinfo

# --- helpers -------------------------------------------------------------------
# submit DIR STUDY FLAGS...: nlvid slurm --submit; sets aid and mid.
submit() {
    local job=$1 study=$2
    shift 2
    local out
    out=$("$nlvid" slurm "$study" --out "$job" --time 10:00 --mem 500M "$@" --submit)
    echo "$out"
    aid=$(sed -n 's/^submitted array job \([0-9]*\).*merge job \([0-9]*\).*/\1/p' <<< "$out")
    mid=$(sed -n 's/^submitted array job \([0-9]*\).*merge job \([0-9]*\).*/\2/p' <<< "$out")
    [ -n "$aid" ] && [ -n "$mid" ] || die "no job ids in: $out"
}
# wait_gone IDS TIMEOUT: until squeue lists none of the jobs.
wait_gone() {
    local t0=$SECONDS
    while [ -n "$(squeue -h -j "$1" 2> /dev/null)" ]; do
        [ $((SECONDS - t0)) -lt "$2" ] || die "jobs $1 still queued after $2 s"
        sleep 0.2
    done
}
# same_export A B: every exported file but timing.csv equal byte for byte.
same_export() {
    local n=0
    for set in train check; do
        for f in X.npy Y.npy t.npy X.csv Y.csv status.csv meta.json; do
            cmp -s "$1/$set/$f" "$2/$set/$f" || die "$set/$f differs between $1 and $2"
            n=$((n + 1))
        done
    done
    echo "byte-identical: $n files (train and check: X, Y, t as npy; X, Y, status as csv; meta.json)"
}
stored() { find "$1" -name '[0-9]*.json' 2> /dev/null | wc -l; }
show_logs() { tail -n 5 "$1"/logs/*.out >&2 || true; }

# --- 1. sharded build == local build --------------------------------------------
say "1. hertz-prony.toml: array of 4 tasks (%2) + merge vs local nlvid build"
p1=$work/p1
mkdir -p "$p1"
cp "$repo/examples/metamodel/hertz-prony.toml" "$p1/study.toml"
"$nlvid" build "$p1/study.toml" --store "$p1/local-store" --export "$p1/local-export" --quiet
submit "$p1/job" "$p1/study.toml" --array-size 4 --throttle 2
wait_gone "$aid,$mid" 120
[ -f "$p1/job/state/merge.ok" ] || { show_logs "$p1/job"; die "the merge job did not finish"; }
same_export "$p1/job/export" "$p1/local-export"

# --- 2. SIGKILL one task mid-run, Slurm requeues it -------------------------------
say "2. slow runs (test_delay 150 ms), task 1's nlvid SIGKILLed mid-run"
p2=$work/p2
mkdir -p "$p2"
sed 's/^model = "hertz-prony"$/&\ntest_delay = "150 ms"/' \
    "$repo/examples/metamodel/hertz-prony.toml" > "$p2/study.toml"
grep -q '^test_delay' "$p2/study.toml" || die "could not add test_delay"
"$nlvid" build "$p2/study.toml" --store "$p2/local-store" --export "$p2/local-export" --quiet
submit "$p2/job" "$p2/study.toml" --array-size 4 --throttle 2
victim=$p2/job/stores/task-1
t0=$SECONDS
pid=
while :; do
    [ $((SECONDS - t0)) -lt 120 ] || die "task 1 never got going"
    pid=$(pgrep -f -- "--store $victim --quiet" | head -n 1 || true)
    if [ -n "$pid" ] && [ "$(stored "$victim/train/runs")" -ge 3 ]; then break; fi
    sleep 0.05
done
kill -KILL "$pid"
killed_at=$(stored "$victim")
echo "SIGKILLed nlvid (pid $pid) of task 1 after $killed_at of its 20 runs"
[ "$killed_at" -lt 20 ] || die "task 1 finished before the kill; slow it down"
wait_gone "$aid,$mid" 300
[ -f "$p2/job/state/merge.ok" ] || { show_logs "$p2/job"; die "the merge job did not finish"; }
log=$p2/job/logs/task-1.out
grep -q 'killed by signal 9' "$log" || die "task 1's log does not show the kill"
grep -q 'attempt 2' "$log" || die "task 1 was not requeued"
resumed=$(sed -n 's/^train: 15 runs in shard: \([0-9]*\) already done.*/\1/p' "$log" | tail -n 1)
echo "task 1 was requeued by Slurm; its second attempt found $resumed of 15 training runs done"
[ "${resumed:-0}" -gt 0 ] || die "the requeued task did not resume from its store"
grep 'nlvid-slurm' "$log" | sed 's/^/    /'
same_export "$p2/job/export" "$p2/local-export"

# --- 3. an array whose tasks fail ---------------------------------------------------
say "3. every task fails (--nlvid /bin/false): the merge is cancelled, --status says what to do"
p3=$work/p3
mkdir -p "$p3"
cp "$p1/study.toml" "$p3/study.toml"
submit "$p3/job" "$p3/study.toml" --array-size 2 --nlvid /bin/false
wait_gone "$aid,$mid" 120
[ ! -f "$p3/job/state/merge.ok" ] || die "the merge ran although every task failed"
set +e
"$nlvid" slurm --status "$p3/job" | tee "$p3/status.txt"
rc=${PIPESTATUS[0]}
set -e
[ "$rc" = 1 ] && grep -q 'FAILED' "$p3/status.txt" && grep -q 'ARRAY=0-1 ' "$p3/status.txt" \
    || die "--status did not report the failed tasks (exit $rc)"
echo "-- doing what it says: generate again with a working nlvid, submit again"
submit "$p3/job" "$p3/study.toml" --array-size 2
wait_gone "$aid,$mid" 120
"$nlvid" slurm --status "$p3/job" | tail -n 1
same_export "$p3/job/export" "$p1/local-export"

# --- 4. benchmark ----------------------------------------------------------------
# bench_study LABEL STUDY TASKS: array of TASKS tasks (1 CPU each) + merge
# against `nlvid build` (2 threads) on the same runs, BENCH_REPEAT times.
bench_study() {
    local label=$1 bstudy=$2 tasks=$3 r b t0 t1 t_local t_array fair
    say "4$label. benchmark: $(basename "$bstudy"), array of $tasks tasks (1 CPU each) vs nlvid build (2 threads)"
    echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
    # Linux autogroup gives every session one equal CPU share on a busy
    # machine, and Slurm starts each task in a session of its own: 2 running
    # tasks would get 2 shares against the 1 of `nlvid build` (run here in
    # its own session with setsid). So each task's session gets autogroup
    # nice 3 (weight 526, about half of nice 0's 1024): equal shares.
    fair=
    if [ "$(cat /proc/sys/kernel/sched_autogroup_enabled 2> /dev/null)" = 1 ]; then
        fair=1
        echo "autogroup on: array tasks at autogroup nice 3, nlvid build in its own session at 0"
    fi
    for r in $(seq "${BENCH_REPEAT:-3}"); do
        b=$work/bench$label-$r
        mkdir -p "$b"
        t0=$(now)
        setsid -w "$nlvid" build "$bstudy" --store "$b/local-store" --export "$b/local-export" \
            --quiet > "$b/local.log" 2>&1
        t_local=$(secs "$t0" "$(now)")
        if [ -n "$fair" ]; then
            (while :; do
                for p in $(pgrep -f -- "--store $b/job/stores/task-"); do
                    { grep -qs 'nice 0' "/proc/$p/autogroup" && echo 3 > "/proc/$p/autogroup"; } 2> /dev/null || true
                done
                sleep 0.02
            done) &
            poller=$!
        fi
        t0=$(now)
        submit "$b/job" "$bstudy" --array-size "$tasks" > /dev/null
        wait_gone "$aid,$mid" 3600
        t_array=$(secs "$t0" "$(now)")
        if [ -n "$poller" ]; then kill "$poller"; wait "$poller" 2> /dev/null || true; poller=; fi
        [ -f "$b/job/state/merge.ok" ] || { show_logs "$b/job"; die "benchmark merge failed"; }
        same_export "$b/job/export" "$b/local-export" > /dev/null
        # From the task logs (epochs at script start and end, nlvid's own
        # wall time): script overhead = task wall - its nlvid build.
        read -r per_task task_sum n < <(awk '
            /task-[0-9]*: start/ {for (i = 1; i <= NF; i++) if ($i == "epoch") s[FILENAME] = $(i + 1)}
            /: done, nlvid build took/ {for (i = 1; i <= NF; i++) {if ($i == "took") b[FILENAME] = $(i + 1); if ($i == "epoch") e[FILENAME] = $(i + 1)}}
            END {for (f in s) {n++; o += e[f] - s[f] - b[f]; w += e[f] - s[f]} printf "%.3f %.3f %d\n", o / n, w, n}' \
            "$b"/job/logs/task-*.out)
        merge_s=$(grep -h ', epoch' "$b"/job/logs/merge-*.out | awk '{print $NF}')
        last_end=$(grep -h ': done, nlvid build took' "$b"/job/logs/task-*.out | awk '{print $NF}' | sort -n | tail -n 1)
        first_start=$(grep -h ': start on' "$b"/job/logs/task-*.out | awk '{print $NF}' | sort -n | head -n 1)
        span=$(secs "$first_start" "$last_end")
        # CPU-seconds the 2 CPUs sat idle between first start and last end,
        # per task (dispatch gaps and the imbalance of the last tasks).
        idle=$(awk "BEGIN {printf \"%.3f\", (2 * $span - $task_sum) / $n}")
        # nlvid's fixed cost per task: a shard build with nothing left to run
        # (start, read the study, make the design, open the store).
        t1=$(now)
        "$nlvid" build "$bstudy" --shard "1/$tasks" --store "$b/job/stores/task-0" --quiet > /dev/null
        fixed=$(secs "$t1" "$(now)")
        echo "run $r: nlvid build ${t_local} s; array + merge ${t_array} s" \
            "(ratio $(awk "BEGIN {r = $t_array / $t_local; printf \"%.3f, %s 15 %%\", r, r <= 1.15 ? \"within\" : \"NOT within\"}")); byte-identical"
        echo "    submit -> first task start $(secs "$t0" "$first_start") s; first start -> last task end ${span} s;" \
            "last task end -> merge done $(secs "$last_end" "$merge_s") s"
        echo "    per task ($n tasks): script overhead ${per_task} s, idle CPU ${idle} s," \
            "nlvid fixed cost (no runs left) ${fixed} s; load $(cut -d' ' -f1-3 /proc/loadavg)"
    done
    echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
}
if [ "$bench" = 1 ]; then
    # a. Runs that sleep (test_delay 400 ms, hertz-prony): CPU contention
    #    from other users hardly matters, so the difference is what Slurm
    #    and the task scripts add.
    sed "s/^model = \"hertz-prony\"\$/&\ntest_delay = \"${BENCH_DELAY:-400 ms}\"/" \
        "$repo/examples/metamodel/hertz-prony.toml" > "$work/sleepy.toml"
    bench_study a "$work/sleepy.toml" "${BENCH_TASKS:-2}"
    # b. A CPU-bound study (the ch. II membrane solver).
    if [ "${BENCH_CPU:-1}" = 1 ]; then
        bench_study b "${BENCH_STUDY:-$repo/examples/metamodel/membrane.toml}" "${BENCH_TASKS:-2}"
    fi
fi


say "all passed"
