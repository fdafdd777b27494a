#!/usr/bin/env bash
# Installs every Debian 12 package sim4cv needs to build, run and test.
# Idempotent: installs only what is missing, and touches apt only then.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config ccache
  libbullet-dev libeigen3-dev libosmesa6-dev libboost-dev libjpeg62-turbo-dev
  protobuf-compiler libprotobuf-dev
  libopencv-dev libopencv-contrib-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-protobuf python3-numpy python3-pytest python3-pip python3-setuptools python3-wheel  # wheel: pip install of clients/python
  python3-opencv  # the Python examples (an OpenCV tracker in the loop)
  python3-matplotlib python3-yaml  # tracking evaluation plots and experiment files
  python3-torch python3-onnx  # the driving network: training on the CPU, ONNX export for OpenCV DNN
  octave liboctave-dev  # the Octave client: mkoctfile --mex, and its tests
  python3-venv dpkg-dev  # the install test: a fresh venv for the wheel, dpkg-shlibdeps for cpack -G DEB
  clang libclang-rt-14-dev  # the fuzz build (scripts/fuzz.sh): clang and its libFuzzer/sanitizer runtimes
  chromium python3-websocket  # the studio's browser tests (tests/studio, tools/cdp_driver.py): headless Chromium over DevTools
  slurmctld slurmd slurm-client munge python3-distributed  # tests/python/test_scaling.py: a one-machine Slurm cluster and Dask (docs/scaling.md)
  opencv-data  # the realism probe (bench/realism_probe.py): OpenCV's Haar full- and upper-body cascades
  sweethome3d-furniture  # the packaged people walkers are drawn with (assets/build_assets.py, docs/assets.md)
  nodejs  # tests/architecture/test_extending.py: the studio's channel list and colours run on a worked-example channel
)

missing=()
for package in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
