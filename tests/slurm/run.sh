#!/bin/bash
# A real one-node Slurm cluster (docs/cluster.md; how it was first set up:
# the Slurm documentation for a one-node cluster): installs slurmctld, slurmd, slurm-client and munge
# when missing (Debian, as root), starts munged (unless running) and the two Slurm daemons
# with a configuration generated in a temporary folder, submits examples/slurm/sweep.sbatch
# as a 4-task job array of a small sweep with `sbatch --wait`, then examples/slurm/merge.sbatch
# behind it (`--dependency=afterok`), and compares the merged CSV with an unsharded run of the
# same sweep (equal except the timing columns); then the same for a frame range
# (examples/slurm/frames.sbatch, outputs compared file by file). Stops the daemons it started by process id.
# Exits non-zero, saying which step, if anything fails.
#
# Usage: tests/slurm/run.sh   (CGNODES=path/to/cgnodes, default $CARGO_TARGET_DIR or target,
# release build; SHARDS=4). With BENCH="SWEEP.json ..." it then runs each sweep file as a
# 1-, 2- and 4-task array on the same cluster and prints the table of docs/cluster.md.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BIN=${CGNODES:-${CARGO_TARGET_DIR:-$ROOT/target}/release/cgnodes}
SHARDS=${SHARDS:-4}
T0=$(date +%s)
fail() {
    echo "tests/slurm/run.sh: FAILED: $*" >&2
    for f in "${TMP:-/nonexistent}"/*.log "${TMP:-/nonexistent}"/job-*.out; do
        [ -f "$f" ] && { echo "--- $f" >&2; tail -n 20 "$f" >&2; }
    done
    exit 1
}
step() { echo "slurm test [$(($(date +%s) - T0)) s]: $*"; }
[ -x "$BIN" ] || fail "no cgnodes binary at $BIN (cargo build --release, or set CGNODES)"
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    step "installing slurmctld slurmd slurm-client munge"
    [ "$(id -u)" = 0 ] || fail "Slurm is missing and installing it needs root"
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q slurmctld slurmd slurm-client munge >/dev/null 2>&1 \
        || { apt-get update -q >/dev/null && apt-get install -y -q slurmctld slurmd slurm-client munge >/dev/null; } \
        || fail "apt-get install slurmctld slurmd slurm-client munge"
fi

TMP=$(mktemp -d /tmp/cgnodes-slurm.XXXXXX)
chmod 755 "$TMP"
PIDS=()
MUNGED_PID=
cleanup() {
    local p
    for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
    for p in "${PIDS[@]}"; do
        for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$p" 2>/dev/null || true
    done
    if [ -n "$MUNGED_PID" ]; then kill "$MUNGED_PID" 2>/dev/null || true; fi
    rm -rf "$TMP"
}
trap cleanup EXIT

# munge: the key the package made (or a new one), and munged as the munge user.
if ! pgrep -x munged >/dev/null; then
    step "starting munged"
    if [ ! -s /etc/munge/munge.key ]; then
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        chown munge:munge /etc/munge/munge.key
        chmod 400 /etc/munge/munge.key
    fi
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    runuser -u munge -- munged || fail "munged did not start"
    for _ in $(seq 50); do [ -s /run/munge/munged.pid ] && break; sleep 0.1; done
    MUNGED_PID=$(cat /run/munge/munged.pid 2>/dev/null || true)
    [ -n "$MUNGED_PID" ] || fail "munged wrote no pid file"
fi
munge -n | unmunge >/dev/null || fail "munge cannot encode and decode a credential"

# Slurm: a configuration of one node in the temporary folder, on ports of its own.
HOST=$(hostname -s)
MEM=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
mkdir -p "$TMP/state" "$TMP/spool"
export SLURM_CONF=$TMP/slurm.conf
cat >"$SLURM_CONF" <<CONF
ClusterName=cgnodes
SlurmctldHost=$HOST
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmUser=root
SlurmdUser=root
MpiDefault=none
StateSaveLocation=$TMP/state
SlurmdSpoolDir=$TMP/spool
SlurmctldPidFile=$TMP/slurmctld.pid
SlurmdPidFile=$TMP/slurmd.pid
SlurmctldLogFile=$TMP/slurmctld.log
SlurmdLogFile=$TMP/slurmd.log
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
ReturnToService=2
NodeName=$HOST CPUs=$(nproc) RealMemory=$MEM State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
step "starting slurmctld and slurmd ($SLURM_CONF)"
slurmctld -D -i -f "$SLURM_CONF" >"$TMP/slurmctld.stdout.log" 2>&1 &
PIDS+=($!)
sleep 1
slurmd -D -f "$SLURM_CONF" >"$TMP/slurmd.stdout.log" 2>&1 &
PIDS+=($!)
up=
for _ in $(seq 60); do
    if sinfo -h -N -o '%T' 2>/dev/null | grep -qx idle; then up=1; break; fi
    sleep 0.5
done
[ -n "$up" ] || fail "the node did not become idle within 30 s ($(sinfo -h -N -o '%T %E' 2>&1))"

# A small sweep: 10 combinations of the arithmetic example graph.
cat >"$TMP/sweep.json" <<JSON
{
  "graph": "$ROOT/graphs/arithmetic.json",
  "vary": [
    {"param": "radius.value", "values": [0.5, 1, 2, 3, 5]},
    {"param": "pi_r2.op", "values": ["mul", "add"]}
  ],
  "repeat": 2,
  "measure": ["pi_r2.value", "area.value"]
}
JSON
export CGNODES=$BIN CGNODES_ROOT=$ROOT SWEEP=$TMP/sweep.json PARTS=$TMP/parts OUT=$TMP/merged
export CHART="--x radius.value"
step "sbatch --wait --array=0-$((SHARDS - 1)) examples/slurm/sweep.sbatch"
A0=$(date +%s.%N)
ARRAY=$(sbatch --parsable --wait --array=0-$((SHARDS - 1)) --export=ALL --cpus-per-task=1 \
    --output="$TMP/job-%A_%a.out" "$ROOT/examples/slurm/sweep.sbatch") \
    || fail "the job array failed (sbatch --wait exit status)"
A1=$(date +%s.%N)
ARRAY=${ARRAY%%;*}
n=$(ls "$PARTS"/part-*.csv 2>/dev/null | wc -l)
[ "$n" = "$SHARDS" ] || fail "$n parts in $PARTS, expected $SHARDS"
step "array $ARRAY done in $(awk -v a="$A0" -v b="$A1" 'BEGIN { printf "%.1f", b - a }') s; merge with --dependency=afterok:$ARRAY"
sbatch --parsable --wait --dependency=afterok:"$ARRAY" --kill-on-invalid-dep=yes --export=ALL \
    --output="$TMP/job-merge.out" "$ROOT/examples/slurm/merge.sbatch" >/dev/null \
    || fail "the merge job failed"
[ -s "$OUT.csv" ] && [ -s "$OUT.svg" ] || fail "the merge wrote no CSV or chart"

step "unsharded run and comparison"
"$BIN" sweep "$TMP/sweep.json" --csv "$TMP/whole.csv" >"$TMP/whole.log" 2>&1 || fail "the unsharded sweep"
# Results without the timing columns (total_ms, ms:NODE); no field here holds a comma.
results() {
    grep -q '"' "$1" && fail "$1 has quoted fields; this comparison splits on commas"
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) t[i] = ($i == "total_ms" || $i ~ /^ms:/) }
             { s = ""; for (i = 1; i <= NF; i++) s = s (i > 1 ? "," : "") (t[i] ? "" : $i); print s }' "$1"
}
results "$OUT.csv" >"$TMP/merged.results"
results "$TMP/whole.csv" >"$TMP/whole.results"
[ "$(wc -l <"$TMP/whole.results")" = 21 ] || fail "the unsharded sweep has $(wc -l <"$TMP/whole.results") lines, expected 21"
diff "$TMP/whole.results" "$TMP/merged.results" >&2 || fail "merged CSV differs from the unsharded run"
step "passed: $SHARDS-task array merged equals the unsharded sweep"

# A frame range: examples/slurm/frames.sbatch as an array sharing one --out and one --cache,
# frames_done.sbatch behind it; the files equal those of one unsharded run.
export GRAPH=$ROOT/graphs/frames_counter.json FRAMES=0..9 OUT=$TMP/frames CACHE=$TMP/cache
step "sbatch --wait --array=0-$((SHARDS - 1)) examples/slurm/frames.sbatch ($FRAMES)"
FARRAY=$(sbatch --parsable --wait --array=0-$((SHARDS - 1)) --export=ALL --cpus-per-task=1 \
    --output="$TMP/job-f%A_%a.out" "$ROOT/examples/slurm/frames.sbatch") \
    || fail "the frame array failed"
sbatch --parsable --wait --dependency=afterok:"${FARRAY%%;*}" --kill-on-invalid-dep=yes \
    --export=ALL --output="$TMP/job-frames-done.out" "$ROOT/examples/slurm/frames_done.sbatch" \
    >/dev/null || fail "the frames check job failed"
"$BIN" run "$GRAPH" --frames "$FRAMES" --out "$TMP/frames_whole" -q --no-report || fail "the unsharded frame run"
# One CSV per frame, each with its provenance sidecar (docs/provenance.md).
[ "$(ls "$TMP/frames_whole" | wc -l)" = 20 ] || fail "the unsharded run wrote $(ls "$TMP/frames_whole" | wc -l) files, expected 10 CSVs and their 10 provenance sidecars"
diff -r "$TMP/frames_whole" "$TMP/frames" >&2 || fail "sharded frames differ from the unsharded run"
step "passed: $SHARDS-task frame array wrote the unsharded run's files (total $(($(date +%s) - T0)) s)"

# Measurements (optional): per sweep and shard count, the array's wall time (first task start
# to last task end, from the tasks' own clocks), the sum of the tasks' times, and the overhead
# per shard against the 1-shard run: (sum - time of 1 shard) / shards.
[ -n "${BENCH:-}" ] || exit 0
echo "| sweep | shards | array wall (s) | sum of shard times (s) | overhead per shard (s) |"
echo "|---|---|---|---|---|"
for sweep in $BENCH; do
    one=
    for n in 1 2 4; do
        rm -rf "$TMP/b"; mkdir -p "$TMP/b"
        sbatch --wait --array=0-$((n - 1)) --cpus-per-task=1 --output="$TMP/job-b-%a.out" \
            --wrap "s=\$(date +%s.%N); '$BIN' sweep '$ROOT/$sweep' --shard auto --threads 1 --csv \"$TMP/b/part-\$SLURM_ARRAY_TASK_ID.csv\" || exit 1; echo \$s \$(date +%s.%N) > \"$TMP/b/t-\$SLURM_ARRAY_TASK_ID\"" \
            >/dev/null || fail "bench array $sweep $n"
        "$BIN" sweep-merge "$TMP"/b/part-*.csv --csv "$TMP/b/all.csv" 2>/dev/null || fail "bench merge $sweep $n"
        read -r wall sum < <(cat "$TMP"/b/t-* | awk '{ if (NR == 1 || $1 < a) a = $1; if (NR == 1 || $2 > b) b = $2; s += $2 - $1 } END { printf "%.1f %.1f\n", b - a, s }')
        [ -n "$one" ] || one=$sum
        echo "| $(basename "$sweep" .json) | $n | $wall | $sum | $(awk -v s="$sum" -v o="$one" -v n="$n" 'BEGIN { printf "%.2f", (s - o) / n }') |"
    done
done
