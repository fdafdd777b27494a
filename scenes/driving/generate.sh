#!/usr/bin/env bash
# Regenerates the 20 driving maps of the autonomous-driving case study
# (paper: 12 training, 4 validation, 4 test maps), each in a desert and an
# urban form that share the road grid and differ only in dressing. Seeds and
# sizes are fixed; the sizes give road lengths close to the paper's
# (13678 m, 4086 m, 4977 m), and 24 extra maps for DAgger drives. Each map's second line records its command, and
# tests/unit/map_shipped_test.cpp checks the files still match it.
# Usage: scenes/driving/generate.sh [PATH/TO/sim4cv_mapgen]   (default: build/tools/sim4cv_mapgen)
set -euo pipefail
cd "$(dirname "$0")/../.."  # paths are relative to the repository root
MAPGEN=${1:-build/tools/sim4cv_mapgen}

# generate SET COUNT FIRST_SEED SIZE: maps NN = 01..COUNT with seeds FIRST_SEED + NN - 1.
generate() {
  local set=$1 count=$2 first_seed=$3 size=$4
  mkdir -p "scenes/driving/$set"
  for ((i = 1; i <= count; i++)); do
    local nn seed
    nn=$(printf '%02d' "$i")
    seed=$((first_seed + i - 1))
    for surroundings in desert urban; do
      "$MAPGEN" --seed "$seed" --size "$size" --surroundings "$surroundings" \
        --name "driving_${set}_${nn}_${surroundings}" --out "scenes/driving/$set/${nn}_${surroundings}.map"
    done
  done
}

generate train 12 101 12x12
generate val 4 201 12x11
generate test 4 301 12x12
# beyond the paper: maps that only DAgger drives (docs/driving.md, "The shipped model"),
# so the model meets turns it was never trained on without touching val or test
generate extra 24 401 12x12
