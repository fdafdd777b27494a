#!/usr/bin/env bash
# The README's two commands:
#   bash scripts/quickstart.sh demo   set up, build, run the daemon with a client in the loop
#   bash scripts/quickstart.sh test   set up, build, run every test (C++, Python, a short run of each fuzzer)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${SIM4CV_BUILD_DIR:-build}

build() {
  bash scripts/setup.sh
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j"$(nproc)"
}

demo() {
  build
  local out=out/demo
  mkdir -p "$out"
  local listen_file
  listen_file=$(mktemp)
  "$BUILD_DIR/server/daemon/sim4cvd" --tcp-port 0 --mode lockstep > "$listen_file" &
  DAEMON_PID=$!
  LISTEN_FILE=$listen_file
  trap 'kill $DAEMON_PID 2>/dev/null || true; rm -f "$LISTEN_FILE"' EXIT
  for _ in $(seq 100); do grep -q listening "$listen_file" && break; sleep 0.1; done
  local port
  port=$(sed -n 's/.*tcp=\([0-9]*\).*/\1/p' "$listen_file")
  [ -n "$port" ] || { echo "sim4cvd did not start"; exit 1; }
  echo "sim4cvd: $(cat "$listen_file")"
  "$BUILD_DIR/clients/cpp/sim4cv_uav_frames" --port "$port" --frames 300 --out "$out" --save 6
  kill -TERM $DAEMON_PID
  wait $DAEMON_PID
  echo "demo: annotated frames in $out/"
}

run_tests() {
  build
  ctest --test-dir "$BUILD_DIR" --output-on-failure -j2
  # A short run of every fuzz target (docs/reliability.md, "Fuzzing"): its own clang build.
  bash scripts/fuzz.sh build
  bash scripts/fuzz.sh short
}

case "${1:-}" in
  demo) demo ;;
  test) run_tests ;;
  *) echo "usage: $0 demo|test" >&2; exit 2 ;;
esac
