"""Sets the goal column of a driving dataset from its routes' junctions
(docs/driving.md, "Goals at junctions"), without rendering again:

    python3 -m sim4cv.driving relabel --dataset DIR [--seed S]

The driving maps' routes turn at junctions (crossroads, T-junctions) where
the road also goes on: from the image alone the way is ambiguous, so the
network takes the goal input (-1 left, 0 straight, +1 right) that the
paper's guided driving uses. A lane pose within GOAL_BEFORE_M before a
junction of its route, or in it, gets the direction the route takes there
(sim4cv.driving_guided.MapGoals); elsewhere a seeded random goal, so the
network learns to ignore the goal where there is no choice. Every view of
a lane pose (the original and its augmented views) gets the pose's goal.
labels.csv is rewritten (the old one kept as labels.csv.bak), the parts too,
with a `junction` column (1: the pose is at a junction of its route, where
the goal decides the way), which `train --junction-weight K` oversamples,
and an `obstacle` column (1: the pose is part of a pass of an obstacle the
dataset placed, its ideal path shifted into the left lane; see
sim4cv.driving_obstacles), which `train --obstacle-weight K` oversamples.
"""

import csv
import os
import shutil
from typing import Dict, Optional

from . import driving_dataset as dd
from . import driving_metrics as dm
from . import driving_obstacles as dob


def relabel(folder: str, seed: int = 0, log=print) -> Dict[str, int]:
    from .driving_route import MapGoals
    import json
    with open(os.path.join(folder, "dataset.json")) as f:
        meta = json.load(f)
    paths = {dd.parse_map(p)["name"]: p for p in meta["settings"]["maps"]}
    with open(os.path.join(folder, "labels.csv"), newline="") as f:
        reader = csv.DictReader(f)
        columns, rows = reader.fieldnames, list(reader)
    goals_of, lanes, poses = {}, {}, {}
    for r in rows:  # the lane pose of each sample: its original view
        if float(r["offset_side_m"]) == 0.0 and float(r["offset_yaw_deg"]) == 0.0:
            poses[(r["map"], r["route"], r["sample"])] = (float(r["view_x"]), float(r["view_y"]))
    counts = {-1: 0, 0: 0, 1: 0, "junction": 0, "obstacle": 0}
    settings = meta["settings"]
    for r in rows:
        key = (r["map"], r["route"], r["sample"])
        if r["map"] not in goals_of:
            goals_of[r["map"]] = MapGoals(paths[r["map"]], seed)
        if (r["map"], r["route"]) not in lanes:  # the ideal path around the obstacles generate placed
            lane = dd.RoutePath(dd.parse_map(paths[r["map"]]), r["route"])
            lanes[(r["map"], r["route"])] = dob.ShiftedPath.placed(lane, settings.get("obstacles", 0),
                                                                   settings["seed"], r["map"])
        ideal = lanes[(r["map"], r["route"])]
        x, y = poses[key]
        u = dm.nearest_u(ideal.lane, x, y)
        maps_goals = goals_of[r["map"]]
        hit = maps_goals.routes[r["route"]].junction_at(u)
        goal = maps_goals(r["route"], u)
        r["goal"] = str(goal)
        r["junction"] = "1" if hit is not None else "0"
        passing = ideal.passing(u, dd.WAYPOINT_STEP_M, dd.WAYPOINT_COUNT)
        r["obstacle"] = "1" if passing else "0"
        counts[goal] += 1
        counts["junction"] += hit is not None
        counts["obstacle"] += passing
    backup = os.path.join(folder, "labels.csv.bak")
    if not os.path.exists(backup):
        shutil.copyfile(os.path.join(folder, "labels.csv"), backup)
    with open(os.path.join(folder, "labels.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns + [c for c in ("junction", "obstacle") if c not in columns])
        w.writeheader()
        w.writerows(rows)
    log("%s: %d rows, %d at junctions, %d passing obstacles; goals -1/0/+1: %d/%d/%d"
        % (folder, len(rows), counts["junction"], counts["obstacle"], counts[-1], counts[0], counts[1]))
    return counts


def main(argv: Optional[list] = None) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving relabel", description=__doc__.split("\n\n")[0])
    p.add_argument("--dataset", required=True, nargs="+")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    for folder in a.dataset:
        relabel(folder, a.seed)
    return 0
