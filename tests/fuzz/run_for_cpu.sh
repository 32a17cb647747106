#!/bin/bash
# Runs one libFuzzer target until it has spent CPU_SECONDS of processor time, then stops it with
# SIGINT (libFuzzer answers with its final stats). CPU time, not wall time, because the machines
# this runs on are shared: a fuzzer beside a learning run gets half a core, and a wall-clock
# budget would then fuzz half as much as it says.
#   run_for_cpu.sh CPU_SECONDS FUZZER [libFuzzer arguments...]
# Exit 0 when the budget was spent without a finding; the fuzzer's own status otherwise.
set -u
cpu_seconds=$1; shift
"$@" & pid=$!
ticks=$(getconf CLK_TCK)
stopped=0
while kill -0 "$pid" 2>/dev/null; do
  sleep 2
  # /proc/PID/stat fields 14 and 15: user and system time in clock ticks.
  used=$(awk -v t="$ticks" '{ print int(($14 + $15) / t) }' "/proc/$pid/stat" 2>/dev/null) || break
  if [ "${used:-0}" -ge "$cpu_seconds" ]; then
    echo "run_for_cpu: ${used} CPU-s spent, stopping $(basename "$1")" >&2
    kill -INT "$pid"; stopped=1; break
  fi
done
wait "$pid"; status=$?
# libFuzzer exits 72 when interrupted: that is the budget ending, not a finding.
if [ "$stopped" = 1 ] && [ "$status" = 72 ]; then exit 0; fi
exit "$status"
