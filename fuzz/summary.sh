#!/usr/bin/env bash
# Prints the fuzzing record of docs/reliability.md from fuzz/logs/*.log (written by run_all.sh):
# per target the seconds fuzzed, inputs executed, coverage, corpus size, and the OOMs, timeouts
# and crashes libFuzzer counted (each a distinct failing input, not a distinct bug).
cd "${FUZZ_DIR:-$(dirname "$0")}"
echo "| target | seconds | executions | exec/s | coverage (edges) | corpus | oom / timeout / crash |"
echo "|---|---|---|---|---|---|---|"
for f in logs/*.log; do
  t=$(basename "$f" .log)
  l=$(grep -E '^#[0-9]+: cov' "$f" | tail -1)
  [ -z "$l" ] && continue
  n=$(sed -E 's/^#([0-9]+):.*/\1/' <<<"$l")
  cov=$(sed -E 's/.*cov: ([0-9]+).*/\1/' <<<"$l")
  corp=$(sed -E 's/.*corp: ([0-9]+).*/\1/' <<<"$l")
  otc=$(sed -E 's/.*oom\/timeout\/crash: ([0-9\/]+).*/\1/' <<<"$l")
  s=$(sed -E 's/.*time: ([0-9]+)s.*/\1/' <<<"$l")
  echo "| $t | $s | $n | $(( n / (s > 0 ? s : 1) )) | $cov | $corp | ${otc//\// \/ } |"
done
