#!/usr/bin/env bash
# Regenerates the four tracking maps from the hand-written layouts in
# layouts/: the road and the route come from the layout, the dressing from
# the seed. Each map's second line records its command, and
# tests/unit/map_shipped_test.cpp checks the files still match it.
# Usage: scenes/tracking/generate.sh [PATH/TO/sim4cv_mapgen]   (default: build/tools/sim4cv_mapgen)
set -euo pipefail
cd "$(dirname "$0")/../.."  # paths in the commands are relative to the repository root
MAPGEN=${1:-build/tools/sim4cv_mapgen}

# Easy: one big loop, gentle curves. Map 1 of the paper's tracking study.
for surroundings in desert urban; do
  "$MAPGEN" --from scenes/tracking/layouts/easy.layout --seed 1 --surroundings "$surroundings" \
    --name "tracking_easy_$surroundings" --out "scenes/tracking/easy_$surroundings.map"
done

# Hard: tight serpentine bends under trees that overhang the road (map 2).
for surroundings in desert urban; do
  "$MAPGEN" --from scenes/tracking/layouts/hard.layout --seed 2 --surroundings "$surroundings" \
    --roadside-trees 0.7 --name "tracking_hard_$surroundings" --out "scenes/tracking/hard_$surroundings.map"
done
