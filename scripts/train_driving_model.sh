#!/bin/bash
# Reproduces the shipped driving model models/driving/ (docs/driving.md,
# "Results"): the datasets, a lane model, the goal model trained from it, then
# that model trained on the guided junction maps too, first as is, then with
# junction samples drawn 3 times as often (the mean of three epochs), then with
# views near the lane, then two rounds of DAgger (the states the model drives
# into, labelled), then parked cars to pass (obstacle data on every training
# map, drawn 3 times as often) and a third DAgger round, on the extra maps and
# with obstacles; last, the fully connected layers alone on right turns through junctions and on that
# model's drives on the extra maps. About 7.5 hours on a 2-core machine.
# Usage: scripts/train_driving_model.sh [WORK_DIR]
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
# the guided driving study's junction maps (docs/driving_guided.md), goals by the same rule
/usr/bin/python3 -m sim4cv.driving_guided generate --maps ../../scenes/driving/guided/train/0{1,2,3}_{desert,urban}.map \
    --out "$W/guided" --straight-step 8 --turn-step 2.5 --random-views 1 --seed 0
run relabel --dataset "$W/guided"
all=("$W/train" "$W/obstacles" "$W/guided")
run train --train "${all[@]}" --val "$W/val" --out "$W/goal_more" --init "$W/goal/model.pt" --goal \
    --lr 1e-4 --batch 32 --epochs 1 --threads 2
# junction weight 3: 5 epochs, every one kept; their last three averaged (driving average)
run train --train "${all[@]}" --val "$W/val" --out "$W/junctions" --init "$W/goal_more/model.pt" --goal \
    --junction-weight 3 --lr 1e-4 --batch 32 --epochs 5 --patience 0 --threads 2 --keep-epochs
run average --models "$W"/junctions/epochs/0{3,4,5}.pt --out "$W/junctions_avg"
# DAgger round 1: the states that model drives into on the training maps, labelled
run dagger --model "$W/junctions_avg/model.onnx" --maps train --out "$W/dagger1"
# near views: the states within 0.5 m and 5 degrees of the lane that closed loop visits
run generate --maps train --straight-step 2.4 --turn-step 0.6 --random-views 1 --offset-range 0.5 --yaw-range 5 \
    --seed 1 --out "$W/near"
/usr/bin/python3 -m sim4cv.driving_guided generate --maps ../../scenes/driving/guided/train/0{1,2,3}_{desert,urban}.map \
    --out "$W/near_guided" --straight-step 8 --turn-step 2.5 --random-views 1 --offset-range 0.5 --yaw-range 5 --seed 1
run relabel --dataset "$W/near" "$W/near_guided"
all+=("$W/near" "$W/near_guided")
run train --train "${all[@]}" --val "$W/val" --out "$W/near_model" --init "$W/junctions_avg/model.pt" --goal \
    --junction-weight 3 --lr 1e-4 --batch 32 --epochs 3 --patience 0 --threads 2 --keep-epochs
# + DAgger round 1 (from near-view epoch 3, the first to complete all 8 validation laps)
all+=("$W/dagger1")
run train --train "${all[@]}" --val "$W/val" --out "$W/dagger_model1" --init "$W/near_model/epochs/03.pt" --goal \
    --junction-weight 3 --lr 1e-4 --batch 32 --epochs 3 --patience 0 --threads 2 --keep-epochs
# DAgger round 2: the states of round 1's epoch 2 (the best of its epochs on the validation maps)
run dagger --model "$W/dagger_model1/epochs/02.pt" --maps train --out "$W/dagger2"
all+=("$W/dagger2")
# two epochs: the second (also the lower validation loss) is this stage's model.onnx, the previous
# shipped model
run train --train "${all[@]}" --val "$W/val" --out "$W/dagger_model2" --init "$W/dagger_model1/epochs/02.pt" --goal \
    --junction-weight 3 --lr 1e-4 --batch 32 --epochs 2 --patience 0 --threads 2 --keep-epochs
# DAgger round 3 with that model (the previous shipped model): the training maps, the extra maps
# (never rendered otherwise) and the training maps with 4 parked cars per route; and obstacle
# data on all 24 training maps
run dagger --model "$W/dagger_model2/model.onnx" --maps train --out "$W/dagger3"
run dagger --model "$W/dagger_model2/model.onnx" --maps ../../scenes/driving/extra/{01..12}_*.map --out "$W/dagger3_extra"
run dagger --model "$W/dagger_model2/model.onnx" --maps train --obstacles 4 --seed 2 --out "$W/dagger3_obstacles"
run generate --maps train --obstacles 4 --straight-step 2.4 --turn-step 0.6 --random-views 3 --seed 2 \
    --out "$W/obstacles_all"
run relabel --dataset "$W/obstacles_all"
all+=("$W/dagger3" "$W/dagger3_extra" "$W/obstacles_all" "$W/dagger3_obstacles")
# samples passing an obstacle drawn 3 times as often too; epoch 2 (also the lower validation loss, so
# this stage's model.onnx) was the previous shipped model (docs/driving.md, "The shipped model")
run train --train "${all[@]}" --val "$W/val" --out "$W/round3" --init "$W/dagger_model2/model.pt" --goal \
    --junction-weight 3 --obstacle-weight 3 --lr 1e-4 --batch 32 --epochs 2 --patience 0 --threads 2 --keep-epochs
# the head alone (docs/driving.md, "Training the head alone"): that model's drives on the 24 extra maps,
# without and with 4 parked cars per route (DAgger rounds 5 and 6), near views at every turn of the
# extra maps and of the junction maps (right turns through junctions), then 8 epochs of the fully
# connected layers on those and the lane, near, obstacle and junction-map sets; the last epoch ships
run dagger --model "$W/round3/model.onnx" --maps extra --out "$W/dagger_extra"
run dagger --model "$W/round3/model.onnx" --maps extra --obstacles 4 --seed 3 --out "$W/dagger_extra_obs"
run generate --maps extra --straight-step 40 --turn-step 0.2 --random-views 2 --offset-range 0.5 --yaw-range 5 \
    --seed 7 --out "$W/extra_turns"
/usr/bin/python3 -m sim4cv.driving_guided generate --maps ../../scenes/driving/guided/train/0{1,2,3}_{desert,urban}.map \
    --out "$W/guided_turns" --straight-step 40 --turn-step 0.5 --random-views 1 --offset-range 0.5 --yaw-range 5 --seed 5
run relabel --dataset "$W/extra_turns" "$W/guided_turns"
run head --init "$W/round3/model.pt" --train "$W/train" "$W/near" "$W/obstacles_all" "$W/guided" "$W/guided_turns" \
    "$W/dagger_extra" "$W/extra_turns" "$W/dagger_extra_obs" --val "$W/val" --out "$W/shipped" --epochs 8 \
    --lr 1e-4 --junction-weight 3 --threads 2 --keep-epochs --last
# the shipped evaluation: steering at waypoint 2 with gain 0.9
run evaluate --model "$W/shipped/model.onnx" --maps val --steer-waypoint 2 --steer-gain 0.9 --out "$W/eval_val"
run evaluate --model "$W/shipped/model.onnx" --maps test --steer-waypoint 2 --steer-gain 0.9 --out "$W/eval"
