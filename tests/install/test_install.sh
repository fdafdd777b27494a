#!/usr/bin/env bash
# sim4cv installed as a user installs it, tested from a folder outside the source tree:
#   1. cmake --install into a temporary prefix; a program of one's own built with
#      find_package(sim4cv) and one with pkg-config each get a frame from the installed sim4cvd;
#   2. cpack -G DEB: the package's control fields and files (dpkg-deb -I/-c), then its contents
#      (dpkg -x) run: sim4cvd --help, and a frame from its daemon through its client library;
#   3. the wheel pip-installed into a fresh venv: `sim4cv --help`, and a frame over shared
#      memory from a daemon the package finds and starts by itself;
#   4. the Octave package pkg-installed into a temporary prefix: pkg load sim4cv, a frame.
# Usage: tests/install/test_install.sh BUILD_DIR (built: sim4cvd, the client, the wheel, the
# Octave package). Exits 0 when all pass, 1 naming the first step that failed.
set -euo pipefail
SOURCE=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(cd "${1:?usage: test_install.sh BUILD_DIR}" && pwd)
WORK=$(mktemp -d /tmp/sim4cv-install-test.XXXXXX)
PREFIX=$WORK/prefix
DAEMON_PID=""
cleanup() {
  if [ -n "$DAEMON_PID" ]; then kill -TERM "$DAEMON_PID" 2> /dev/null || true; wait "$DAEMON_PID" 2> /dev/null || true; fi
  rm -rf "$WORK"
}
trap cleanup EXIT
fail() { echo "test_install: FAILED: $*"; exit 1; }
step() { echo "test_install: $* ($SECONDS s)"; }
cd "$WORK"  # a user's folder: nothing here comes from the source tree by accident

# start_daemon BINARY [FLAGS...]: sets DAEMON_PID and LINE (its listening line).
start_daemon() {
  "$@" --tcp-port 0 --mode lockstep > "$WORK/daemon.out" 2> "$WORK/daemon.err" &
  DAEMON_PID=$!
  for _ in $(seq 1 600); do
    LINE=$(head -n 1 "$WORK/daemon.out" 2> /dev/null || true)
    [[ $LINE == "sim4cvd listening "* ]] && return 0
    kill -0 "$DAEMON_PID" 2> /dev/null || break
    sleep 0.1
  done
  cat "$WORK/daemon.err"
  fail "$1 printed no listening line"
}
stop_daemon() { kill -TERM "$DAEMON_PID"; wait "$DAEMON_PID" || fail "sim4cvd exited with status $?"; DAEMON_PID=""; }
field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<< "$LINE"; }
expect_frame() {  # expect_frame WHAT OUTPUT: OUTPUT must report a 320x180 frame
  grep -Eq '^frame [0-9]+ 320x180 rgb_mean [0-9.]+' <<< "$2" || fail "$1 got no frame: $2"
  echo "  $1: $2"
}

step "cmake --install into $PREFIX"
cmake --install "$BUILD" --prefix "$PREFIX" > install.log || { cat install.log; fail "cmake --install"; }
for file in bin/sim4cvd bin/sim4cv_mapgen lib/libsim4cv-client.so lib/libsim4cv-client.a include/sim4cv/client.h \
            include/sim4cv/protocol/shm_sync.h include/sim4cv.pb.h lib/cmake/sim4cv/sim4cvConfig.cmake \
            lib/cmake/sim4cv/sim4cvConfigVersion.cmake lib/pkgconfig/sim4cv.pc share/sim4cv/protocol/sim4cv.proto \
            share/sim4cv/scenes/tracking/easy_urban.map share/sim4cv/studio/index.html share/sim4cv/models/driving \
            share/sim4cv/ASSETS-ATTRIBUTION.md; do
  [ -e "$PREFIX/$file" ] || fail "cmake --install left out $file"
done

# The installed daemon serves the installed studio, not the source tree's: a marked copy shows it.
echo "<!-- installed copy $$ -->" >> "$PREFIX/share/sim4cv/studio/index.html"
start_daemon "$PREFIX/bin/sim4cvd" --shm-name "/sim4cv-install-$$" --shm-channels rgb --http-port 0
PAGE=$(/usr/bin/python3 -c 'import sys, urllib.request; print(urllib.request.urlopen(sys.argv[1], timeout=30).read().decode())' \
       "http://127.0.0.1:$(field http)/index.html") || fail "the installed daemon's studio page"
[[ $PAGE == *"<!-- installed copy $$ -->"* ]] || fail "the installed sim4cvd did not serve PREFIX/share/sim4cv/studio"
step "find_package(sim4cv): a program of one's own"
cmake -S "$SOURCE/tests/install/consumer" -B consumer -DCMAKE_PREFIX_PATH="$PREFIX" > consumer.log 2>&1 &&
  cmake --build consumer >> consumer.log 2>&1 || { cat consumer.log; fail "the find_package(sim4cv) program did not build"; }
expect_frame "find_package over TCP" "$(consumer/get_frame "tcp://127.0.0.1:$(field tcp)")"

step "pkg-config sim4cv: the same program by hand"
export PKG_CONFIG_PATH=$PREFIX/lib/pkgconfig
# shellcheck disable=SC2046  # pkg-config's flags are words
g++ -std=c++20 -O1 -o pc_get_frame "$SOURCE/tests/install/consumer/get_frame.cpp" $(pkg-config --cflags --libs sim4cv) ||
  fail "the pkg-config program did not build"
expect_frame "pkg-config over shm" "$(LD_LIBRARY_PATH=$PREFIX/lib ./pc_get_frame "shm://$(field shm)")"
stop_daemon

step "cpack -G DEB"
(cd "$BUILD" && cpack -G DEB -B "$WORK/deb" > "$WORK/cpack.log" 2>&1) || { cat cpack.log; fail "cpack -G DEB"; }
DEB=$(ls deb/sim4cv_*_amd64.deb) || fail "cpack made no sim4cv_VERSION_amd64.deb"
dpkg-deb -I "$DEB" > deb-info.txt
grep -q '^ Package: sim4cv$' deb-info.txt || fail "the package is not named sim4cv: $(cat deb-info.txt)"
grep -Eq '^ Depends: .*libprotobuf[0-9]+ ' deb-info.txt || fail "Depends lacks the protobuf runtime: $(grep Depends deb-info.txt)"
! grep -Eq '^ Depends: .*-dev' deb-info.txt || fail "Depends names a -dev package: $(grep Depends deb-info.txt)"
grep -q 'conffiles' deb-info.txt || fail "the package has no conffiles"
dpkg-deb -c "$DEB" > deb-files.txt
for file in ./usr/bin/sim4cvd ./usr/lib/libsim4cv-client.so ./usr/lib/cmake/sim4cv/sim4cvConfig.cmake \
            ./usr/lib/pkgconfig/sim4cv.pc ./usr/lib/systemd/system/sim4cvd.service ./etc/default/sim4cvd \
            ./usr/share/sim4cv/studio/index.html ./usr/share/sim4cv/ASSETS-ATTRIBUTION.md; do
  grep -q " $file\( \|$\)" deb-files.txt || fail "the .deb lacks $file"
done
dpkg -x "$DEB" debroot
export LD_LIBRARY_PATH=$WORK/debroot/usr/lib
HELP=$(debroot/usr/bin/sim4cvd --help) && [[ $HELP == *"Usage: sim4cvd [flags]"* ]] || fail "the packaged sim4cvd --help: $HELP"
start_daemon debroot/usr/bin/sim4cvd
expect_frame "the .deb's daemon and client library" "$(./pc_get_frame "tcp://127.0.0.1:$(field tcp)")"
stop_daemon
unset LD_LIBRARY_PATH

step "pip install of the wheel into a fresh venv"
/usr/bin/python3 -m venv --system-site-packages venv
WHEEL=$(ls "$BUILD"/clients/python/dist/sim4cv-*.whl) || fail "the build made no wheel"
venv/bin/pip install --quiet --no-index --no-build-isolation "$WHEEL" || fail "pip install $WHEEL"
HELP=$(venv/bin/sim4cv --help) && [[ $HELP == *"usage: sim4cv COMMAND"* ]] || fail "sim4cv --help: $HELP"
venv/bin/sim4cv experiment --help > /dev/null || fail "sim4cv experiment --help"
set +e; venv/bin/sim4cv no-such-command 2> /dev/null; status=$?; set -e
[ $status -eq 2 ] || fail "sim4cv no-such-command exited $status, not 2"
OUTPUT=$(env -u SIM4CVD PATH="$PREFIX/bin:$PATH" venv/bin/python "$SOURCE/tests/install/get_frame.py") ||
  fail "the pip-installed package got no frame: $OUTPUT"
[[ $OUTPUT == *" from $WORK/venv/"*" with $PREFIX/bin/sim4cvd" ]] || fail "not the venv's sim4cv with the installed daemon: $OUTPUT"
expect_frame "pip-installed sim4cv over shm" "$OUTPUT"

if command -v octave > /dev/null; then
  step "pkg install of the Octave package"
  OCTAVE_PACKAGE=$(ls "$PREFIX"/share/sim4cv/octave/sim4cv-*.tar.gz) || fail "no Octave package installed"
  mkdir -p octave
  start_daemon "$PREFIX/bin/sim4cvd"
  # Octave's package lists go to a HOME of its own; the daemon wrote its access token under the
  # real one, so the token travels in SIM4CV_TOKEN, as for any client that cannot read the file.
  TOKEN=$(cat "${XDG_RUNTIME_DIR:-$HOME/.cache}/sim4cv/tcp-$(field tcp).token") || fail "no access token file for the daemon"
  OUTPUT=$(SIM4CV_TOKEN=$TOKEN HOME=$WORK octave --no-gui --no-window-system --quiet --no-history --eval "
    pkg prefix $WORK/octave/packages $WORK/octave/packages; pkg local_list $WORK/octave/octave_packages;
    pkg global_list $WORK/octave/global_packages;
    pkg install $OCTAVE_PACKAGE; ADDRESS = 'tcp://127.0.0.1:$(field tcp)'; source('$SOURCE/tests/install/get_frame.m');" 2>&1) ||
    fail "the Octave package got no frame: $OUTPUT"
  OUTPUT=$(grep '^frame ' <<< "$OUTPUT" || true)
  [[ $OUTPUT == *" from $WORK/octave/packages/"* ]] || fail "not the pkg-installed functions: $OUTPUT"
  expect_frame "Octave package" "$OUTPUT"
  stop_daemon
else
  echo "test_install: octave not installed: the Octave package is not tested"
fi
step "all passed"
