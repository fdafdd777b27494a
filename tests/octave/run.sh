#!/usr/bin/env bash
# The Octave client's tests against the real daemon: client_test.m over TCP,
# UDP and shared memory (it kills its daemon at the end), then mosse_test.m
# with a fresh daemon. Usage: tests/octave/run.sh [BUILD_DIR] (default build).
# Exits non-zero on any failure.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(cd "${1:-$ROOT/build}" && pwd)
DAEMON=$BUILD/server/daemon/sim4cvd
MEX_DIR=$BUILD/clients/matlab
for need in "$DAEMON" "$MEX_DIR/sim4cv_mex.mex"; do
  [ -e "$need" ] || { echo "run.sh: $need is missing; build first (cmake --build build --target sim4cvd sim4cv_octave)"; exit 2; }
done
command -v octave > /dev/null || { echo "run.sh: octave is not installed"; exit 2; }

WORK=$(mktemp -d /tmp/sim4cv-octave-test.XXXXXX)
PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2> /dev/null; done
  for pid in "${PIDS[@]}"; do wait "$pid" 2> /dev/null; done
  rm -rf "$WORK"
}
trap cleanup EXIT

# start_daemon TAG: starts sim4cvd with its stdout in $WORK/TAG.out (drained
# by the file, never a pipe), waits for the listening line and sets PID,
# TCP, UDP, SHM.
start_daemon() {
  local tag=$1 line=""
  "$DAEMON" --tcp-port 0 --udp-port 0 --shm-name "/sim4cv-octave-$$-$tag" --shm-channels rgb,depth,mask \
    --mode lockstep > "$WORK/$tag.out" 2> "$WORK/$tag.err" &
  PID=$!
  PIDS+=("$PID")
  for _ in $(seq 1 200); do
    line=$(head -n 1 "$WORK/$tag.out" 2> /dev/null)
    [[ $line == "sim4cvd listening "* ]] && break
    kill -0 "$PID" 2> /dev/null || break
    sleep 0.05
  done
  if [[ $line != "sim4cvd listening "* ]]; then
    echo "run.sh: sim4cvd ($tag) did not print its listening line:"; cat "$WORK/$tag.err"; return 1
  fi
  TCP=$(sed -n 's/.* tcp=\([0-9]*\).*/\1/p' <<< "$line")
  UDP=$(sed -n 's/.* udp=\([0-9]*\).*/\1/p' <<< "$line")
  SHM=$(sed -n 's/.* shm=\([^ ]*\).*/\1/p' <<< "$line")
}

# OCTAVE_PRELOAD: libraries Octave alone needs preloaded (a sanitizer's runtime for an
# instrumented MEX file; the shell and the daemon must not get them).
run_octave() {
  LD_PRELOAD=${OCTAVE_PRELOAD:-${LD_PRELOAD:-}} octave --no-gui --no-window-system --quiet --no-history \
    --eval "addpath('$ROOT/clients/matlab', '$ROOT/clients/matlab/examples', '$MEX_DIR', '$ROOT/tests/octave'); $1"
}

status=0
echo "run.sh: client_test kills its daemon with SIGKILL at the end, on purpose (bash reports it as Killed)"
start=$SECONDS
start_daemon client || exit 1
if run_octave "client_test('tcp://127.0.0.1:$TCP', 'udp://127.0.0.1:$UDP', 'shm://$SHM', $PID)"; then
  echo "run.sh: client_test passed"
else
  echo "run.sh: client_test FAILED"; status=1
fi

start_daemon mosse || exit 1
if run_octave "mosse_test('shm://$SHM')"; then
  echo "run.sh: mosse_test passed"
else
  echo "run.sh: mosse_test FAILED"; status=1
fi
echo "run.sh: $((SECONDS - start)) s, status $status"
exit $status
