#!/usr/bin/env bash
# The whole test suite, several times in a row, beside busy loops that keep
# every core busy (as `stress --cpu N` does): tests must pass on a machine
# running a parallel build, and none may take more than its 300 s.
#   bash scripts/busy_suite.sh [BUILD_DIR] [PASSES] [BUSY_LOOPS]
# Defaults: build, 3 passes, one busy loop per core (nproc). Each pass's
# CTest output goes to BUILD_DIR/busy_suite/pass-K.log; the summary (tests
# passed, the slowest test, wall time, load average) to standard output.
# Exit status 0 only if every pass passed.
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
PASSES=${2:-3}
LOOPS=${3:-$(nproc)}
LOGS="$BUILD_DIR/busy_suite"
mkdir -p "$LOGS"

BUSY_PIDS=()
stop_busy() {
  for pid in "${BUSY_PIDS[@]}"; do kill "$pid" 2>/dev/null; done
  wait "${BUSY_PIDS[@]}" 2>/dev/null
}
trap stop_busy EXIT
for _ in $(seq "$LOOPS"); do
  bash -c 'while :; do :; done' &
  BUSY_PIDS+=($!)
done
echo "busy_suite: $LOOPS busy loops (pids ${BUSY_PIDS[*]}), $PASSES passes of ctest -j2 in $BUILD_DIR, $(nproc) cores"

failed=0
for pass in $(seq "$PASSES"); do
  log="$LOGS/pass-$pass.log"
  start=$(date +%s)
  ctest --test-dir "$BUILD_DIR" --output-on-failure -j2 > "$log" 2>&1
  status=$?
  seconds=$(( $(date +%s) - start ))
  summary=$(grep -E "tests passed|tests failed" "$log" | tail -1)
  slowest=$(grep -E "Test +#[0-9]+: .* sec$" "$log" | awk '{print $(NF-1), $4}' | sort -rn | head -1)
  echo "pass $pass: status $status, $summary, slowest: ${slowest:-?} s, wall ${seconds} s, load $(cut -d' ' -f1-3 /proc/loadavg)"
  grep -E "\*\*\*(Failed|Timeout)|Failed +[0-9.]+ sec|Not Run" "$log" | sed 's/^/  /'
  [ "$status" -eq 0 ] || failed=1
done
exit $failed
