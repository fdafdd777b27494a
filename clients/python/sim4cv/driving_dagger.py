"""The states a trained model drives into, rendered and labelled (DAgger,
Ross et al. 2011; docs/driving.md, "States the model visits"):

    python3 -m sim4cv.driving dagger --model OUT/model.onnx --maps train --out DIR [--obstacles N]

The augmented views teach recovery from offsets drawn from fixed ranges; a
model in closed loop makes its own, and at a junction a few degrees it has
seen too rarely can be answered with a turn the wrong way, which the next
frames make worse. This drives every route of the maps with the model
(driving_eval.drive_route, with the goals the evaluation gives); where the
car gets more than --takeover metres off the ideal path the reference policy
takes over until it is back, so one mistake does not end the lap and the
states of the mistake and of the recovery are both recorded. The poses off
the lane (more than --min-offset metres or --min-yaw degrees from the lane
pose at the same arc length, and within the augmentation's ranges) are then
rendered from the first-person camera, at most one per --every metres, each
with the lane pose's own view, and labelled like augmented views: the lane
pose's four waypoints re-encoded for the pose driven. Goals and the
`junction` column as `relabel` sets them. With --obstacles N the drives
and the renders meet the cars `generate --obstacles N --seed S` parks, the
ideal path passes them in the left lane, and the "lane pose" is that path's
pose (relabel's `obstacle` column marks the pass). DIR/drives holds the
drives (driving.json, runs/*.csv); DIR is a dataset for `train` like any other.
"""

import csv
import math
import os
import sys
from typing import Dict, List, Optional, Sequence

from . import driving_control as dc
from . import driving_dataset as dd
from . import driving_eval as de
from . import driving_labels as dl
from . import driving_obstacles as dob

DEFAULT_TAKEOVER_M = 1.0  # the lane departure distance: beyond it the reference policy drives
DEFAULT_EVERY_M = 0.5     # one pose per this much progress along the route at most
DEFAULT_MIN_OFFSET_M = 0.1
DEFAULT_MIN_YAW_DEG = 2.0


def pick_poses(rows: Sequence[dict], lane, every_m: float = DEFAULT_EVERY_M,
               min_offset_m: float = DEFAULT_MIN_OFFSET_M, min_yaw_deg: float = DEFAULT_MIN_YAW_DEG) -> List:
    """generate_map's poses of one route from a drive's rows (driving_eval's
    ROW_COLUMNS, as dicts): [(u, [lane view, driven view]), ...]. `lane`:
    the ideal path, a RoutePath or (with obstacles) a ShiftedPath."""
    picked, last_u = [], -math.inf
    for r in rows:
        u, x, y = float(r["u"]), float(r["x"]), float(r["y"])
        if u - last_u < every_m:
            continue
        lx, ly, lyaw = lane.point(u)
        yaw = math.radians(float(r["yaw_deg"]))
        side = (x - lx) * math.sin(lyaw) - (y - ly) * math.cos(lyaw)  # positive right, as offset_pose
        turn = math.degrees(math.remainder(yaw - lyaw, 2.0 * math.pi))  # positive left
        if abs(side) < min_offset_m and abs(turn) < min_yaw_deg:
            continue
        if abs(side) > dl.RANDOM_OFFSET_M or abs(turn) > dl.RANDOM_YAW_DEG:
            continue  # beyond what the labels of an augmented view mean
        picked.append((u, [(lx, ly, lyaw, 0.0, 0.0), (x, y, yaw, side, turn)]))
        last_u = u
    return picked


def collect(policy, maps: Sequence[str], surroundings: Sequence[str], out: str, takeover_m: float,
            every_m: float, min_offset_m: float, min_yaw_deg: float,
            controller: dc.Controller = dc.Controller(steer_waypoint=2), speed: float = de.DEFAULT_SPEED,
            seed: int = 0, obstacles: int = 0, log=print) -> dict:
    """Drives `policy` (a driving_eval policy: NetworkPolicy, or any with
    waypoints()) over the maps, then renders the poses off the lane into the
    dataset `out`; returns dataset.json's content."""
    from .driving_route import MapGoals
    from .driving_relabel import relabel
    if takeover_m <= de.TAKEBACK_M:
        raise dd.DatasetError("--takeover %g: more than %g m (the reference policy hands back within %g m)"
                              % (takeover_m, de.TAKEBACK_M, de.TAKEBACK_M))
    if every_m <= 0:
        raise dd.DatasetError("--every must be positive, got %g" % every_m)
    if obstacles < 0:
        raise dd.DatasetError("--obstacles must be 0 or more, got %d" % obstacles)
    settings = {"model": getattr(policy, "path", None) or policy.name, "takeover_m": takeover_m,
                "every_m": every_m, "min_offset_m": min_offset_m, "min_yaw_deg": min_yaw_deg,
                **controller.settings(), "speed_m_s": speed}
    if obstacles:  # only when used, so the datasets made before obstacles still match on a rerun
        settings["obstacles"] = obstacles
    _check_out(out, settings)
    drives = os.path.join(out, "drives")
    if not os.path.isfile(os.path.join(drives, "driving.json")):  # a rerun reuses finished drives
        de.evaluate(policy, maps, surroundings, drives, speed, log=log, controller=controller,
                    takeover_m=takeover_m, seed=seed, obstacles=obstacles)

    def poses(path: str) -> Dict[str, List]:
        info = dd.parse_map(path)
        plan = {}
        for route in info["routes"]:
            with open(os.path.join(drives, "runs", "%s_%s.csv" % (info["name"], route)), newline="") as f:
                rows = list(csv.DictReader(f))
            ideal = dob.ShiftedPath.placed(dd.RoutePath(info, route), obstacles, seed, info["name"])
            plan[route] = pick_poses(rows, ideal, every_m, min_offset_m, min_yaw_deg)
        return plan

    meta = dd.generate(maps, surroundings, out, views="none", seed=seed, log=log, poses=poses, obstacles=obstacles,
                       goals=lambda path: MapGoals(path, seed), extra_settings={"dagger": settings})
    relabel(out, seed, log=log)
    return meta


def _check_out(out: str, settings: dict) -> None:
    """Refuses, before any driving, a DIR that cannot be written or that
    holds a dataset of other settings (dd.generate checks the rest)."""
    import json
    try:
        os.makedirs(os.path.join(out, "drives"), exist_ok=True)
    except OSError as e:
        raise dd.DatasetError("output folder %s is not writable: %s" % (out, e)) from None
    for name in ("dataset.json", os.path.join("drives", "driving.json")):
        try:
            with open(os.path.join(out, name)) as f:
                old = json.load(f)["settings"]
        except FileNotFoundError:
            continue
        except (OSError, ValueError, KeyError) as e:
            raise dd.DatasetError("%s is unreadable (%s); refusing to overwrite it" % (os.path.join(out, name), e))
        old = old.get("dagger") if name == "dataset.json" else {
            "model": old.get("model"), "takeover_m": old.get("takeover_m"), "speed_m_s": old.get("speed_m_s"),
            "obstacles": old.get("obstacles") or None,
            **{k: old.get(k, v) for k, v in dc.Controller().settings().items()}}  # older ones: the defaults
        mine = settings if name == "dataset.json" else {k: settings.get(k) for k in old}
        if old != mine:
            raise dd.DatasetError("%s holds a dagger dataset of other settings (%s, not %s); use another --out; "
                                  "nothing was overwritten" % (out, old, mine))


def main(argv: Optional[List[str]] = None) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving dagger", description=__doc__.split("\n\n")[0])
    p.add_argument("--model", required=True, help="model.onnx or model.pt of a --goal model (or a lane model)")
    p.add_argument("--maps", nargs="+", default=["train"], help="train, val, test, extra and/or map files")
    p.add_argument("--surroundings", default="desert,urban")
    p.add_argument("--out", required=True, help="the dataset folder")
    p.add_argument("--takeover", type=float, default=DEFAULT_TAKEOVER_M,
                   help="metres off the ideal path from which the reference policy drives (default %(default)s)")
    p.add_argument("--every", type=float, default=DEFAULT_EVERY_M, help="metres between poses at least")
    p.add_argument("--min-offset", type=float, default=DEFAULT_MIN_OFFSET_M,
                   help="a pose is rendered from this many metres off the lane ...")
    p.add_argument("--min-yaw", type=float, default=DEFAULT_MIN_YAW_DEG, help="... or this many degrees")
    dc.add_arguments(p, steer_waypoint=2)
    p.add_argument("--speed", type=float, default=de.DEFAULT_SPEED)
    p.add_argument("--seed", type=int, default=0, help="goals, and the obstacles' places as generate --seed")
    p.add_argument("--obstacles", type=int, default=0, help="cars parked per route, as generate --obstacles")
    a = p.parse_args(argv)
    surroundings = [s for s in a.surroundings.split(",") if s]
    controller = dc.from_arguments(p, a)
    try:
        policy = de.NetworkPolicy(a.model)
        policy.path = os.path.abspath(a.model)
        collect(policy, a.maps, surroundings, a.out, a.takeover, a.every, a.min_offset, a.min_yaw,
                controller, a.speed, a.seed, a.obstacles)
    except (dd.DatasetError, de.EvalError, RuntimeError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0
