#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 600) with JOBS targets at a time (default 1),
# continuing past crashes so one run finds them all; logs go to fuzz/logs/<target>.log and
# crashing inputs to fuzz/artifacts/<target>/. Per-input limits: 5 s (sanitizer builds run
# 2-3x slower than release, so this is the 2 s budget of docs/reliability.md) and 2 GiB.
# Usage: fuzz/run_all.sh [SECONDS] [JOBS] [targets...]   (needs nightly + cargo-fuzz)
set -uo pipefail
cd "$(dirname "$0")"
secs=${1:-600}; jobs=${2:-1}; shift 2 2>/dev/null || shift $#
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(graph_json graph_f3d obj mtl off ply usda npy csv image plugin_manifest plugin_reply)
mkdir -p logs
run() {
  local t=$1
  mkdir -p "artifacts/$t" "corpus/$t"
  cargo +nightly fuzz run -O "$t" "corpus/$t" -- -max_total_time="$secs" -timeout=5 \
    -rss_limit_mb=2048 -malloc_limit_mb=2048 -fork=1 -ignore_crashes=1 -ignore_ooms=1 \
    -ignore_timeouts=1 -artifact_prefix="artifacts/$t/" -print_final_stats=1 > "logs/$t.log" 2>&1
  echo "$t done: $(grep -E '^#[0-9]+' "logs/$t.log" | tail -1)"
}
export -f run; export secs
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'run {}'
