#!/usr/bin/env bash
# The libFuzzer targets in fuzz/ (docs/reliability.md, "Fuzzing"):
#   bash scripts/fuzz.sh build        configure and build build-fuzz (clang, ASan+UBSan, coverage)
#   bash scripts/fuzz.sh short [S]    each target for S seconds (default 15); fails on any crash,
#                                     leak or timeout (the test command runs this)
#   bash scripts/fuzz.sh long [N]     each target for N executions (default 10000000), one at a
#                                     time, logs in build-fuzz/logs/; fails on any finding
#                                     (FUZZ_MAX_SECONDS=S: at most S seconds per target;
#                                     FUZZ_WORKERS=W: W processes per target at once)
#   bash scripts/fuzz.sh seeds        rewrite the seed corpora in fuzz/corpus from real messages
#   bash scripts/fuzz.sh merge        add to fuzz/corpus what the runs found (-set_cover_merge=1), keeping
#                                     every named seed and 512 KB per target (FUZZ_CORPUS_BUDGET_BYTES)
# Targets: all by default, or name some in FUZZ_TARGETS="fuzz_map fuzz_runlog".
# A finding is written to build-fuzz/findings/<target>/; replay it with build-fuzz/fuzz/<target> FILE.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${SIM4CV_FUZZ_BUILD_DIR:-build-fuzz}
ALL_TARGETS="fuzz_envelope fuzz_udp_datagram fuzz_udp_reassembler fuzz_map fuzz_runlog fuzz_configure fuzz_shm fuzz_websocket_json"
TARGETS=${FUZZ_TARGETS:-$ALL_TARGETS}

build() {
  CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -DSIM4CV_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only" > /dev/null
  cmake --build "$BUILD_DIR" -j"$(nproc)" --target sim4cv_fuzz sim4cv_fuzz_seeds
}

# The flags every run gets, and each target's own: inputs up to the size its
# decoder reads (a client's whole shm area; a whole small run log), and a dictionary.
flags() {
  local target=$1
  echo "-rss_limit_mb=2048 -timeout=10 -print_final_stats=1"
  case $target in
    fuzz_shm) echo "-max_len=16640" ;;
    fuzz_runlog) echo "-max_len=20000" ;;  # the default scene's 61-frame seed is 17 KB
    *) echo "-max_len=8192" ;;
  esac
  [ -f "fuzz/$target.dict" ] && echo "-dict=fuzz/$target.dict"
  return 0
}

# run TARGET LOG LIBFUZZER_ARGS...: new inputs go to a scratch corpus, never into fuzz/corpus.
run() {
  local target=$1 log=$2
  shift 2
  local scratch="$BUILD_DIR/scratch/$target" findings="$BUILD_DIR/findings/$target"
  mkdir -p "$scratch" "$findings" "$(dirname "$log")"
  # shellcheck disable=SC2046
  if ! "$BUILD_DIR/fuzz/$target" $(flags "$target") -artifact_prefix="$findings/" "$@" \
      "$scratch" "fuzz/corpus/$target" > "$log" 2>&1; then
    echo "fuzz: $target FAILED (log: $log, input: $findings/)"
    grep -E 'ERROR|SUMMARY|Test unit written' "$log" | head -5
    return 1
  fi
  summary "$target" "$log"
}

# One line per run: executions, seconds, rate, coverage.
summary() {
  local target=$1 log=$2
  local runs time rate cov
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  time=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  cov=$(grep -E '^#[0-9]+' "$log" | tail -1 | grep -oE 'cov: [0-9]+ ft: [0-9]+' || true)
  printf 'fuzz: %-22s ok  %10s runs  %5s s  %7s exec/s  %s\n' "$target" "$runs" "${time:-?}" "$rate" "$cov"
}

short() {
  local seconds=${1:-15} failed=0
  for target in $TARGETS; do
    run "$target" "$BUILD_DIR/logs/$target.short.log" -max_total_time="$seconds" || failed=1
  done
  return $failed
}

# FUZZ_MAX_SECONDS caps each target's wall-clock time as well (a slow target stops short of N).
# FUZZ_WORKERS=W splits each target's N executions over W processes at once (one per core),
# sharing the scratch corpus, each with its own seed and log ($target.long.K.log); the first
# N mod W workers run one more, so the counts add up to N.
long() {
  local runs=${1:-10000000} workers=${FUZZ_WORKERS:-1} failed=0 cap=()
  [ -n "${FUZZ_MAX_SECONDS:-}" ] && cap=(-max_total_time="$FUZZ_MAX_SECONDS")
  for target in $TARGETS; do
    if ((workers == 1)); then
      run "$target" "$BUILD_DIR/logs/$target.long.log" -runs="$runs" "${cap[@]}" || failed=1
      continue
    fi
    local pids=() k
    for ((k = 1; k <= workers; k++)); do
      run "$target" "$BUILD_DIR/logs/$target.long.$k.log" -runs=$((runs / workers + (k <= runs % workers))) \
        -seed="$k" "${cap[@]}" &
      pids+=($!)
    done
    for k in "${pids[@]}"; do wait "$k" || failed=1; done
  done
  return $failed
}

seeds() {
  "$BUILD_DIR/fuzz/sim4cv_fuzz_seeds" . fuzz/corpus
  record_log default "" 2.5
  record_log easy_urban "--map scenes/tracking/easy_urban.map" 1.5
  # A run that ended in a crash: the log's last record torn.
  head -c 3000 fuzz/corpus/fuzz_runlog/easy_urban.s4log > fuzz/corpus/fuzz_runlog/easy_urban_torn.s4log
  echo "fuzz: seeds written to fuzz/corpus/"
}

# record_log NAME DAEMON_FLAGS SECONDS: a real run log from the daemon of the normal build (SIM4CVD).
record_log() {
  local sim4cvd=${SIM4CVD:-build/server/daemon/sim4cvd} out="fuzz/corpus/fuzz_runlog/$1.s4log"
  mkdir -p fuzz/corpus/fuzz_runlog
  rm -f "$out"
  # shellcheck disable=SC2086
  "$sim4cvd" --tcp-port 0 --udp-port -1 --mode realtime $2 --log "$out" --log-label fuzz-seed 2> /dev/null &
  local pid=$!
  sleep "$3"
  kill -TERM $pid
  wait $pid
}

# What merge commits per target: the named seeds, then what the runs found
# that adds coverage, within a byte budget (8 targets x 512 KB = 4 MB in all),
# so the repository does not grow with every session's runs.
CORPUS_BUDGET_BYTES=${FUZZ_CORPUS_BUDGET_BYTES:-524288}

# Files libFuzzer named by their SHA-1; every other name is a seed someone chose
# (hand-written, written by sim4cv_fuzz_seeds, or a finding's reproducer).
is_hash_name() { [[ $(basename "$1") =~ ^[0-9a-f]{40}$ ]]; }

# The named seeds go into the merge's output folder first: -set_cover_merge=1
# keeps what that folder holds and adds from the committed corpus and the run's
# scratch corpus only inputs that cover something the folder does not.
merge() {
  for target in $TARGETS; do
    local corpus="fuzz/corpus/$target" merged="$BUILD_DIR/merged/$target" picked="$BUILD_DIR/merged/$target.picked"
    rm -rf "$merged" "$picked"
    mkdir -p "$merged" "$picked" "$BUILD_DIR/logs" "$BUILD_DIR/scratch/$target"
    local file
    for file in "$corpus"/*; do is_hash_name "$file" || cp "$file" "$merged/"; done
    # shellcheck disable=SC2046
    if ! "$BUILD_DIR/fuzz/$target" $(flags "$target") -set_cover_merge=1 "$merged" "$corpus" \
        "$BUILD_DIR/scratch/$target" > "$BUILD_DIR/logs/$target.merge.log" 2>&1; then
      echo "fuzz: $target merge FAILED (log: $BUILD_DIR/logs/$target.merge.log); $corpus unchanged"
      return 1
    fi
    # The named seeds whole, then the found inputs smallest first while the budget lasts.
    local used=0 left_out=0 size
    for file in "$merged"/*; do
      is_hash_name "$file" && continue
      cp "$file" "$picked/"
      used=$((used + $(stat -c %s "$file")))
    done
    while read -r size file; do
      if ((used + size > CORPUS_BUDGET_BYTES)); then
        left_out=$((left_out + 1))
        continue
      fi
      cp "$file" "$picked/"
      used=$((used + size))
    done < <(find "$merged" -maxdepth 1 -type f -regextype posix-extended -regex '.*/[0-9a-f]{40}' \
               -printf '%s %p\n' | sort -n)
    rm -rf "$corpus"
    mv "$picked" "$corpus"
    echo "fuzz: $target corpus: $(find "$corpus" -type f | wc -l) files, $((used / 1024)) KB" \
      "(budget $((CORPUS_BUDGET_BYTES / 1024)) KB; $left_out found inputs over it left out)"
  done
}

case "${1:-}" in
  build) build ;;
  short) short "${2:-15}" ;;
  long) long "${2:-10000000}" ;;
  seeds) seeds ;;
  merge) merge ;;
  *) echo "usage: $0 build|short [SECONDS]|long [RUNS]|seeds|merge" >&2; exit 2 ;;
esac
