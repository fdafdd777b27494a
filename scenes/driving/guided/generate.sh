#!/usr/bin/env bash
# Regenerates the guided-driving maps (docs/driving_guided.md): larger maps
# with T-junctions and crossroads, each in a desert and an urban form that
# share the road grid and routes and differ only in dressing.
#   1. sim4cv_mapgen makes the roads (and the closed route 'loop') from a seed;
#   2. `python3 -m sim4cv.driving_guided layout` adds open routes g01, g02, ...
#      that together take every choice (left, straight, right from every arm)
#      of every junction, and writes the layout to layouts/SET_NN.layout;
#   3. sim4cv_mapgen --from LAYOUT dresses it (desert and urban).
# Each map's second line records its step-3 command, and each layout's header
# its steps 1 and 2; tests/unit/map_shipped_test.cpp checks the maps still
# match their commands.
# Usage: scenes/driving/guided/generate.sh [PATH/TO/sim4cv_mapgen]   (default: build/tools/sim4cv_mapgen)
set -euo pipefail
cd "$(dirname "$0")/../../.."  # paths are relative to the repository root
MAPGEN=${1:-build/tools/sim4cv_mapgen}
PYTHON=${PYTHON:-/usr/bin/python3}
DIR=scenes/driving/guided

# generate SET NN SIZE SEED: roads of `sim4cv_mapgen --size SIZE --seed SEED`,
# routes from the same seed, dressed with it.
generate() {
  local set=$1 nn=$2 size=$3 seed=$4
  local base layout="$DIR/layouts/${set}_${nn}.layout"
  base=$(mktemp --suffix=.map)
  mkdir -p "$DIR/layouts" "$DIR/$set"
  "$MAPGEN" --seed "$seed" --size "$size" --surroundings desert --name "guided_${set}_${nn}" --out "$base" >/dev/null
  PYTHONPATH=clients/python "$PYTHON" -m sim4cv.driving_guided layout --base "$base" --seed "$seed" \
    --name "guided_${set}_${nn}" --out "$layout" \
    --comment "Layout of the guided-driving map $set/$nn (docs/driving_guided.md), made by $DIR/generate.sh:" \
    --comment "roads and route loop: sim4cv_mapgen --seed $seed --size $size --surroundings desert --name guided_${set}_${nn}" \
    --comment "routes g01...: python3 -m sim4cv.driving_guided layout --seed $seed (every choice of every junction)"
  rm -f "$base"
  for surroundings in desert urban; do
    "$MAPGEN" --from "$layout" --seed "$seed" --surroundings "$surroundings" \
      --name "guided_${set}_${nn}_${surroundings}" --out "$DIR/$set/${nn}_${surroundings}.map"
  done
}

generate train 01 16x16 93
generate train 02 16x16 60
generate train 03 16x16 109
generate train 04 20x20 135
generate test 01 16x16 40
generate test 02 20x20 122
