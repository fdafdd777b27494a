#!/usr/bin/env bash
# Builds pybullet (Bullet's Python module, zlib licence, github.com/bulletphysics/bullet3)
# from source for bench/bench_vs_pybullet.py. Not run by tests or setup.sh and nothing it
# builds is committed: Debian 12 does not package pybullet and PyPI may be unreachable.
#
# Usage: bash bench/build_pybullet.sh SRC [DEST]
#   SRC   a bullet3 source tree (a git checkout, `git archive HEAD | tar -x`, or the Debian
#         source package's tree from `apt-get source bullet`) containing setup.py
#   DEST  where the built module goes (default /work/pybullet/site); then run the benchmark with
#         PYTHONPATH=DEST /usr/bin/python3 bench/bench_vs_pybullet.py
# Needs python3-dev and python3-numpy (pybullet then returns camera images as numpy arrays,
# its fast path). Built with the interpreter's own flags (Debian's -O2), minus debug info,
# two compile jobs (the build machine is shared); about 25 minutes on two busy cores.
set -euo pipefail
SRC=$(realpath "$1")
DEST=$(realpath -m "${2:-/work/pybullet/site}")
JOBS=${PYBULLET_JOBS:-2}
cd "$SRC"
# setup.py compiles with 2 x cpu_count threads; cap it so the shared machine stays usable.
sed -i "s/^  N = 2 \* multiprocessing.cpu_count().*/  N = $JOBS/" setup.py
grep -q "^  N = $JOBS\$" setup.py
export CC="ccache gcc" CXX="ccache g++" CFLAGS="-g0"
nice -n 5 /usr/bin/python3 setup.py build_ext --build-lib "$DEST" --build-temp "$SRC/build_tmp"
# pybullet_data (URDFs: plane, racecar) next to the module, as the PyPI wheel ships it.
rm -rf "$DEST/pybullet_data"
cp -r examples/pybullet/gym/pybullet_data "$DEST/pybullet_data"
PYTHONPATH="$DEST" /usr/bin/python3 -c "import pybullet, pybullet_data; print('pybullet', pybullet.getAPIVersion(), 'numpy', pybullet.isNumpyEnabled())"
