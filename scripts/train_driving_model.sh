#!/bin/bash
# Reproduces the shipped driving model models/driving/ (docs/driving.md,
# "Results"): the datasets, a lane model, then the goal model trained from it.
# About 2 hours on a 2-core machine. Usage: scripts/train_driving_model.sh [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/../clients/python"
W=${1:-/tmp/sim4cv_driving}
run() { /usr/bin/python3 -m sim4cv.driving "$@"; }
run generate --maps train --straight-step 2.4 --turn-step 0.6 --random-views 3 --out "$W/train"
run generate --maps ../../scenes/driving/train/0[1-3]_*.map --obstacles 2 --straight-step 2.4 --turn-step 0.6 \
    --random-views 3 --out "$W/obstacles"
run generate --maps val --random-views 1 --out "$W/val"
run relabel --dataset "$W/train" "$W/obstacles" "$W/val"
# the lane model: its goal column is ignored (no --goal)
run train --train "$W/train" "$W/obstacles" --val "$W/val" --out "$W/lane" --lr 3e-4 --batch 32 --patience 4 \
    --epochs 40 --max-minutes 45 --threads 2
run train --train "$W/train" "$W/obstacles" --val "$W/val" --out "$W/goal" --init "$W/lane/model.pt" --goal \
    --lr 2e-4 --batch 32 --patience 4 --epochs 40 --max-minutes 30 --threads 2
run evaluate --model "$W/goal/model.onnx" --maps test --steer-waypoint 2 --out "$W/eval"
