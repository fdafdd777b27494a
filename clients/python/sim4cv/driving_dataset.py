"""The driving case study's labelled dataset (docs/driving.md, "Dataset").

    python3 -m sim4cv.driving_dataset generate --maps train --surroundings desert,urban --out DIR \
        [--views random|fixed|none] [--random-views N] [--straight-step 0.8] [--turn-step 0.2] \
        [--max-samples N] [--seed S]

For each map a lockstep sim4cvd of its own (--map, no traffic) renders a
world-fixed camera "dataset_cam" placed where the car's first-person camera
car_front (CAMERA_SETTINGS) would be for a car standing on the right-lane
centre of every route of the map, tangent to it, and at augmented views
around it (the map's car and UAV are removed); the labels are the lane points 2, 4, 6, 8 m
ahead of the lane pose, encoded for each view (sim4cv.driving_labels).
"""

import argparse
import csv
import glob
import json
import math
import os
import shutil
import sys
import tempfile
import time
import zlib
from typing import Optional, Sequence, Tuple

import numpy as np

from . import driving_labels as dl
from . import driving_obstacles as dob

CAMERA = "dataset_cam"
# The car's first-person camera, "car_front" of every map scene (server/sim/scene.cpp):
# 2.35 m ahead of the body's centre (just past the bumper), 0.3 m above it,
# pitched 5 degrees down. The dataset renders it from a world-fixed camera
# placed where car_front would be for a car standing at the view's pose.
CAMERA_SETTINGS = {"name": "car_front", "width": 320, "height": 180, "fov_y_deg": 60.0, "pitch_down_deg": 5.0,
                   "forward_m": 2.35, "above_body_m": 0.3}
# --ego-car: the car spawned under each view (its headlights light the road ahead at dusk and
# night, as the driven car's do in closed loop), and the gap it keeps to a parked car (closer,
# the two would overlap and physics would shove one of them)
EGO_NAME = "ego"
EGO_CLEARANCE_M = 0.2
BODY_HEIGHT_M = 0.8774  # the car's body centre above the ground at rest (when the map has no car to measure)
WAYPOINT_STEP_M = 2.0
WAYPOINT_COUNT = 4
TURN_LOOKAHEAD_M = 2.0
TURN_THRESHOLD_DEG = 3.0
LANE_OFFSET_M = 2.0  # lane centre to the right of the road centre line (docs/maps.md)
EVAL_STEP_M = 2.0    # default step of the val and test sets
SETS = ("train", "val", "test", "extra")  # extra: maps only DAgger drives (scenes/driving/generate.sh)
FORMAT_VERSION = 1
COLUMNS = (["image", "map", "surroundings", "route", "sample", "view_x", "view_y", "view_yaw_deg",
            "offset_side_m", "offset_yaw_deg"]
           + ["%s%d" % (k, i) for i in range(1, WAYPOINT_COUNT + 1) for k in ("v", "h")] + ["goal"])


class DatasetError(RuntimeError):
    """A dataset cannot be generated into DIR; nothing was overwritten."""


# ---------------------------------------------------------------------------
# Maps and the exact lane geometry of their routes (docs/maps.md)

_NORMALS = {"N": (0.0, 1.0), "S": (0.0, -1.0), "E": (1.0, 0.0), "W": (-1.0, 0.0)}


MAP_HEADER = "sim4cv-map 1"
DEFAULT_TILE_SIZE_M = 20.0        # docs/maps.md: a map without a tile_size line
DEFAULT_SURROUNDINGS = "desert"   # docs/maps.md: a map without a surroundings line


def parse_map(path: str) -> dict:
    """name, surroundings, tile_size, grid (W, H), rows (the grid's H rows),
    routes {name: (closed, [(col, row), ...])} and objects [(kind, x, y, yaw_deg)]
    of a map file (docs/maps.md: the one reader of every Python driving tool;
    tile_size and surroundings default as the daemon's parser defaults them).
    The daemon checks the rest (CheckMap); this refuses only what it cannot read."""
    info = {"name": None, "surroundings": DEFAULT_SURROUNDINGS, "tile_size": DEFAULT_TILE_SIZE_M, "grid": None,
            "rows": [], "routes": {}, "objects": [], "path": path}
    current, header_seen, grid_left = None, False, 0
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise DatasetError("%s: cannot read the map: %s" % (path, e)) from None
    for number, raw in enumerate(lines, 1):
        if grid_left:  # a grid row: '#' is a road tile here, not a comment
            info["rows"].append(raw.strip())
            grid_left -= 1
            continue
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        if not header_seen:
            if " ".join(words) != MAP_HEADER:
                raise DatasetError("%s line %d: expected the header '%s', found '%s'" % (path, number, MAP_HEADER, raw))
            header_seen = True
            continue
        key = words[0]
        try:
            if key == "name":
                info["name"] = words[1]
            elif key == "surroundings":
                info["surroundings"] = words[1]
            elif key == "tile_size":
                info["tile_size"] = float(words[1])
            elif key == "grid":
                info["grid"] = (int(words[1]), int(words[2]))
                grid_left = info["grid"][1]
            elif key == "route":
                current = words[1]
                info["routes"][current] = (words[2] == "closed", [])
            elif key == "object":
                info["objects"].append((words[1], float(words[2]), float(words[3]), float(words[4])))
            elif key == "tiles" and current is not None:
                info["routes"][current][1].extend(tuple(int(v) for v in w.split(",")) for w in words[1:])
        except (IndexError, ValueError):
            raise DatasetError("%s line %d '%s': cannot read its values" % (path, number, raw.strip())) from None
    if info["name"] is None or info["grid"] is None:
        raise DatasetError("%s: not a sim4cv map (no name or grid line)" % path)
    if grid_left:
        raise DatasetError("%s: the grid ends after %d of its %d rows" % (path, len(info["rows"]), info["grid"][1]))
    return info


def _side(a, b) -> str:
    dc, dr = b[0] - a[0], b[1] - a[1]
    sides = {(1, 0): "E", (-1, 0): "W", (0, -1): "N", (0, 1): "S"}
    if (dc, dr) not in sides:
        raise DatasetError("route tiles %s and %s are not neighbours" % (a, b))
    return sides[(dc, dr)]


class RoutePath:
    """The right-lane centre line of a route: straight lines and quarter
    circles, exact, as the daemon's RoadGraph builds them."""

    def __init__(self, map_info: dict, route: str):
        closed, tiles = map_info["routes"][route]
        t = map_info["tile_size"]
        w, h = map_info["grid"]
        self.closed = closed
        self.segments = []  # (start_u, length, kind, params)
        n = len(tiles)
        indices = range(n) if closed else range(1, n - 1)
        u = 0.0
        for i in indices:
            tile, prev, nxt = tiles[i], tiles[(i - 1) % n], tiles[(i + 1) % n]
            ox, oy = (tile[0] + 0.5 - w / 2.0) * t, (h / 2.0 - tile[1] - 0.5) * t
            n_in, n_out = _NORMALS[_side(tile, prev)], _NORMALS[_side(tile, nxt)]
            if n_in == n_out:
                raise DatasetError("route %r turns back at tile %s (U-turns are not supported)" % (route, tile))
            d_in, d_out = (-n_in[0], -n_in[1]), n_out
            half = t / 2.0
            entry = (ox + half * n_in[0] + LANE_OFFSET_M * d_in[1], oy + half * n_in[1] - LANE_OFFSET_M * d_in[0])
            if n_in == (-n_out[0], -n_out[1]):
                length = t
                params = (entry, math.atan2(d_in[1], d_in[0]))
                self.segments.append((u, length, "line", params))
            else:
                cx, cy = ox + half * (n_in[0] + n_out[0]), oy + half * (n_in[1] + n_out[1])
                r = math.hypot(entry[0] - cx, entry[1] - cy)
                ccw = 1.0 if d_in[0] * d_out[1] - d_in[1] * d_out[0] > 0 else -1.0
                length = r * math.pi / 2.0
                params = (cx, cy, r, math.atan2(entry[1] - cy, entry[0] - cx), ccw)
                self.segments.append((u, length, "arc", params))
            u += length
        self.length = u

    def point(self, u: float) -> Tuple[float, float, float]:
        """(x, y, heading rad) at arc length u (wrapping on a closed route)."""
        if self.closed:
            u %= self.length
        u = min(max(u, 0.0), self.length)
        lo, hi = 0, len(self.segments) - 1
        while lo < hi:  # last segment starting at or before u
            mid = (lo + hi + 1) // 2
            if self.segments[mid][0] <= u:
                lo = mid
            else:
                hi = mid - 1
        start, length, kind, p = self.segments[lo]
        s = min(u - start, length)
        if kind == "line":
            (ex, ey), heading = p
            return ex + s * math.cos(heading), ey + s * math.sin(heading), heading
        cx, cy, r, a0, ccw = p
        a = a0 + ccw * s / r
        return cx + r * math.cos(a), cy + r * math.sin(a), _wrap(a + ccw * math.pi / 2.0)


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def lane_samples(path: RoutePath, straight_step: float, turn_step: float):
    """Arc lengths to sample: turn_step where the heading changes by more
    than TURN_THRESHOLD_DEG over the next TURN_LOOKAHEAD_M, else straight_step;
    an open route stops where the last waypoint still lies on it."""
    end = path.length if path.closed else path.length - WAYPOINT_STEP_M * WAYPOINT_COUNT
    u = 0.0
    while u < end - 1e-9:
        yield u
        turn = abs(_wrap(path.point(u + TURN_LOOKAHEAD_M)[2] - path.point(u)[2])) > math.radians(TURN_THRESHOLD_DEG)
        u += turn_step if turn else straight_step


# ---------------------------------------------------------------------------
# Selecting maps

def resolve_maps(specs: Sequence[str], surroundings: Sequence[str], scenes_dir: Optional[str] = None):
    """[(path, set or "")] for --maps values: train|val|test or map files."""
    from .daemon import REPO_ROOT
    scenes_dir = scenes_dir or os.path.join(REPO_ROOT, "scenes", "driving")
    out = []
    for spec in specs:
        if spec in SETS:
            found = []
            for surr in surroundings:
                found += glob.glob(os.path.join(scenes_dir, spec, "*_%s.map" % surr))
            if not found:
                raise DatasetError("no %s maps of surroundings %s in %s" % (spec, ",".join(surroundings), scenes_dir))
            out += [(os.path.abspath(p), spec) for p in sorted(found)]
        else:
            if not os.path.isfile(spec):
                raise DatasetError("--maps %s: neither train, val, test, extra nor a map file" % spec)
            parent = os.path.basename(os.path.dirname(os.path.abspath(spec)))
            out.append((os.path.abspath(spec), parent if parent in SETS else ""))
    return out


def map_steps(map_set: str, straight_step: Optional[float], turn_step: Optional[float]) -> Tuple[float, float]:
    default_straight, default_turn = (EVAL_STEP_M, EVAL_STEP_M) if map_set in ("val", "test") else (0.8, 0.2)
    return (straight_step if straight_step is not None else default_straight,
            turn_step if turn_step is not None else default_turn)


# ---------------------------------------------------------------------------
# The output folder

def _write_json(path: str, data: dict) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def check_out_dir(out: str, settings: dict) -> Optional[dict]:
    """Refuses (DatasetError) an unwritable DIR or one holding another
    dataset; returns the existing dataset.json (same settings) or None."""
    try:
        os.makedirs(out, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=out)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise DatasetError("output folder %s is not writable: %s" % (out, e)) from None
    meta_path = os.path.join(out, "dataset.json")
    if os.path.exists(meta_path):
        try:
            with open(meta_path) as f:
                meta = json.load(f)
        except (OSError, ValueError) as e:
            raise DatasetError("%s is unreadable (%s); refusing to overwrite it" % (meta_path, e)) from None
        old = meta.get("settings")
        if old != json.loads(json.dumps(settings)):
            diff = sorted(k for k in set(old or {}) | set(settings) if (old or {}).get(k) != settings.get(k))
            raise DatasetError("%s holds a dataset made with other settings (differing: %s); "
                               "use another --out or the same settings; nothing was overwritten"
                               % (out, ", ".join(diff)))
        return meta
    for name in ("labels.csv", "images"):
        if os.path.exists(os.path.join(out, name)):
            raise DatasetError("%s holds %s but no dataset.json: not a dataset of this generator; "
                               "refusing to overwrite it" % (out, name))
    return None


def _rebuild_labels(out: str, meta: dict) -> None:
    tmp = os.path.join(out, "labels.csv.tmp")
    with open(tmp, "w", newline="") as dst:
        dst.write(",".join(COLUMNS) + "\n")
        for name in meta["order"]:
            if meta["maps"].get(name, {}).get("complete"):
                with open(os.path.join(out, "parts", name + ".csv")) as src:
                    shutil.copyfileobj(src, dst)
    os.replace(tmp, os.path.join(out, "labels.csv"))


# ---------------------------------------------------------------------------
# Generating one map

def generate_map(path: str, map_set: str, out: str, settings: dict, log=print, goal_fn=None, poses=None) -> dict:
    """Renders and labels one map into out/images/<name>/ and out/parts/<name>.csv.
    goal_fn(route, u, sample) -> -1|0|1, if given, sets the goal column of each lane
    pose's images (guided driving, sim4cv.driving_guided); without it the goal is 0.
    poses: {route: [(u, views), ...]}, if given, renders exactly these views
    (view_x, view_y, view_yaw, sideways_m, yaw_offset_deg), each labelled with the
    waypoints of the lane pose at u, instead of the lane samples and their
    augmented views (the states a model drove into: sim4cv.driving_dagger)."""
    import cv2
    import sim4cv
    from .daemon import OwnDaemon

    info = parse_map(path)
    name = info["name"]
    straight_step, turn_step = map_steps(map_set, settings["straight_step"], settings["turn_step"])
    rng = np.random.default_rng([settings["seed"], zlib.crc32(name.encode())])
    cam = CAMERA_SETTINGS
    img_dir = os.path.join(out, "images", name)
    os.makedirs(img_dir)
    part_path = os.path.join(out, "parts", name + ".csv")
    counts = {"samples": 0, "images": 0, "junction_turns": 0, "max_lane_error_m": 0.0, "obstacles": 0}
    ego_car = bool(settings.get("ego_car"))
    if ego_car:
        counts["views_inside_parked_cars"] = 0
    t0 = time.monotonic()
    flags = ["--map", path, "--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0"]
    if settings.get("conditions"):
        flags += ["--conditions", settings["conditions"]]
    if settings.get("randomize"):  # domain randomisation: new conditions for every image
        flags += ["--randomize", str(settings["randomize"] + zlib.crc32(name.encode())), "--randomize-every", "1"]
    with OwnDaemon(flags, mode="lockstep") as daemon, \
            sim4cv.connect(daemon.address, name="driving_dataset", timeout=30.0) as client, \
            open(part_path, "w", newline="") as part:
        writer = csv.writer(part)
        world = client.get_world()
        heights = {e.id: e.position.z for e in client.get_state().entities}
        body_z = BODY_HEIGHT_M
        for entity in world.entities:
            if entity.name == "car":
                body_z = heights[entity.id]  # at rest on its wheels
            if entity.name in ("car", "uav"):  # the map's car (and the UAV filming it) must not be seen
                client.remove(entity.id)
        camera_z = body_z + cam["above_body_m"]
        client.add_camera(CAMERA, width=cam["width"], height=cam["height"], fov_y_deg=cam["fov_y_deg"],
                          pitch_down_deg=cam["pitch_down_deg"], offset=(0.0, 0.0, camera_z))
        client.subscribe(CAMERA, ["rgb"], "lockstep")
        index = 0
        for route in world.routes:
            if route not in info["routes"]:
                raise DatasetError("%s: route %r of the daemon's WorldInfo is not in the map file" % (path, route))
            lane = RoutePath(info, route)
            # cars parked in the lane; the ideal path passes them in the left lane
            ideal = dob.ShiftedPath.placed(lane, settings.get("obstacles", 0), settings["seed"], name)
            parked = ideal.obstacle_poses()
            for ox, oy, oyaw in parked:
                client.spawn("car", dob.OBSTACLE_NAME % counts["obstacles"], ox, oy, 0.0, math.degrees(oyaw))
                counts["obstacles"] += 1
            planned = poses.get(route, []) if poses is not None else (
                (u, None) for u in lane_samples(lane, straight_step, turn_step))
            for u, views in planned:
                if settings["max_samples"] and counts["samples"] >= settings["max_samples"]:
                    break
                x, y, yaw = ideal.point(u)
                geometric = [ideal.point(u + WAYPOINT_STEP_M * k)[:2] for k in range(1, WAYPOINT_COUNT + 1)]
                lx, ly, lyaw = lane.point(u)
                road = client.query_road(lx, ly, count=WAYPOINT_COUNT, step=WAYPOINT_STEP_M,
                                         heading_deg=math.degrees(lyaw))
                counts["max_lane_error_m"] = max(counts["max_lane_error_m"], road.distance)
                if road.distance > 0.25:
                    raise DatasetError("%s route %r at %.1f m: the lane geometry is %.2f m off the daemon's lane"
                                       % (name, route, u, road.distance))
                queried = [(p.position.x, p.position.y) for p in road.ahead]
                if ideal.passing(u, WAYPOINT_STEP_M, WAYPOINT_COUNT):
                    waypoints = geometric  # passing an obstacle: off the daemon's lane on purpose
                elif len(queried) == WAYPOINT_COUNT and all(
                        math.hypot(a[0] - b[0], a[1] - b[1]) < 0.05 for a, b in zip(queried, geometric)):
                    waypoints = queried
                else:  # QueryRoad goes straight on at a junction where the route turns
                    waypoints = geometric
                    counts["junction_turns"] += 1
                goal = int(goal_fn(route, u, counts["samples"])) if goal_fn is not None else 0
                aug = settings["augmentation"]
                if views is None:
                    views = dl.all_views(x, y, yaw, settings["views"], rng, settings["random_views"],
                                         aug["random_offset_m"], aug["random_yaw_deg"])
                for vx, vy, vyaw, off_m, off_deg in views:
                    if ego_car and any(dob.cars_overlap((vx, vy, vyaw), pose, EGO_CLEARANCE_M) for pose in parked):
                        counts["views_inside_parked_cars"] += 1  # a car cannot stand there: not rendered
                        continue
                    client.set_camera_pose(CAMERA, vx + cam["forward_m"] * math.cos(vyaw),
                                           vy + cam["forward_m"] * math.sin(vyaw), camera_z, math.degrees(vyaw),
                                           cam["pitch_down_deg"])
                    ego = client.spawn("car", EGO_NAME, vx, vy, 0.0, math.degrees(vyaw)) if ego_car else None
                    frame = client.step_and_receive(timeout=30.0)
                    if ego is not None:
                        client.remove(ego)
                    rel = os.path.join("images", name, "%06d.png" % index)
                    if not cv2.imwrite(os.path.join(out, rel), np.ascontiguousarray(frame.image("rgb")[:, :, ::-1])):
                        raise DatasetError("could not write %s" % os.path.join(out, rel))
                    labels = dl.encode(vx, vy, vyaw, waypoints)
                    writer.writerow([rel, name, info["surroundings"], route, counts["samples"],
                                     "%.4f" % vx, "%.4f" % vy, "%.4f" % math.degrees(vyaw),
                                     "%.4f" % off_m, "%.4f" % off_deg]
                                    + ["%.4f" % c for vh in labels for c in vh] + [goal])
                    index += 1
                    counts["images"] += 1
                counts["samples"] += 1
        seconds = time.monotonic() - t0
    counts.update(seconds=round(seconds, 2), images_per_s=round(counts["images"] / max(seconds, 1e-9), 2),
                  straight_step=straight_step, turn_step=turn_step, path=path, complete=True)
    log("%s: %d samples, %d images in %.1f s (%.1f images/s)"
        % (name, counts["samples"], counts["images"], seconds, counts["images_per_s"]))
    return counts


def generate(maps: Sequence[str], surroundings: Sequence[str], out: str, views: str = "random",
             random_views: int = dl.DEFAULT_RANDOM_VIEWS, straight_step: Optional[float] = None,
             turn_step: Optional[float] = None, max_samples: int = 0, seed: int = 0, conditions: str = "",
             randomize: int = 0, obstacles: int = 0, log=print, scenes_dir: Optional[str] = None,
             goals=None, extra_settings: Optional[dict] = None, offset_range: float = dl.RANDOM_OFFSET_M,
             yaw_range: float = dl.RANDOM_YAW_DEG, poses=None, ego_car: bool = False) -> dict:
    """Generates (or resumes) the dataset in `out`; returns dataset.json's content.
    scenes_dir: where the train/val/test sets are (default scenes/driving);
    goals(map_path) -> goal_fn (generate_map's) whose summary() goes into the
    map's counts as "goals"; extra_settings: recorded with the settings (and
    compared on resume). sim4cv.driving_guided uses the three. offset_range,
    yaw_range: the random views' ranges (+-metres, +-degrees); narrow ones
    (e.g. 0.5 m, 5 deg) render the states a driving model visits near the lane.
    poses(map_path) -> generate_map's poses: the views to render instead.
    ego_car: a car stands under every view (spawned for the image, then
    removed), so the image has its headlights and shadow as the driven car's
    camera sees them; views where it would stand inside a parked car are not
    rendered (dataset.json counts them)."""
    if views not in dl.VIEW_MODES:
        raise DatasetError("--views %s: one of %s" % (views, ", ".join(dl.VIEW_MODES)))
    if not (0 <= offset_range <= dl.RANDOM_OFFSET_M and 0 <= yaw_range <= dl.RANDOM_YAW_DEG):
        raise DatasetError("--offset-range %g and --yaw-range %g: within [0, %g] m and [0, %g] degrees"
                           % (offset_range, yaw_range, dl.RANDOM_OFFSET_M, dl.RANDOM_YAW_DEG))
    resolved = resolve_maps(maps, surroundings, scenes_dir)
    settings = {
        "format": FORMAT_VERSION, "maps": [p for p, _ in resolved], "surroundings": list(surroundings),
        "views": views, "random_views": random_views if views == "random" else 0,
        "straight_step": straight_step, "turn_step": turn_step, "max_samples": max_samples, "seed": seed,
        "conditions": conditions, "randomize": randomize, "obstacles": obstacles,
        "camera": dict(CAMERA_SETTINGS, rendered_by=CAMERA),
        "waypoints": {"count": WAYPOINT_COUNT, "step_m": WAYPOINT_STEP_M},
        "augmentation": {"random_offset_m": float(offset_range), "random_yaw_deg": float(yaw_range),
                         "fixed_offsets_m": list(dl.FIXED_OFFSETS_M), "fixed_yaws_deg": list(dl.FIXED_YAWS_DEG)},
        "turn": {"lookahead_m": TURN_LOOKAHEAD_M, "threshold_deg": TURN_THRESHOLD_DEG},
    }
    if ego_car:  # recorded only when on, so datasets made before the option still resume
        settings["ego_car"] = True
    settings.update(extra_settings or {})
    meta = check_out_dir(out, settings)
    names = [parse_map(p)["name"] for p, _ in resolved]
    if meta is None:
        meta = {"settings": settings, "maps": {}, "order": names}
    os.makedirs(os.path.join(out, "parts"), exist_ok=True)
    t0 = time.monotonic()
    made = 0
    for (path, map_set), name in zip(resolved, names):
        if meta["maps"].get(name, {}).get("complete"):
            log("%s: complete, skipped" % name)
            continue
        shutil.rmtree(os.path.join(out, "images", name), ignore_errors=True)  # interrupted: redo
        meta["maps"][name] = {"complete": False}
        _write_json(os.path.join(out, "dataset.json"), meta)
        goal_fn = goals(path) if goals else None
        meta["maps"][name] = generate_map(path, map_set, out, settings, log, goal_fn=goal_fn,
                                          poses=poses(path) if poses else None)
        if goal_fn is not None:
            meta["maps"][name]["goals"] = goal_fn.summary()
        made += meta["maps"][name]["images"]
        _rebuild_labels(out, meta)
        _update_counts(meta)
        _write_json(os.path.join(out, "dataset.json"), meta)
    _rebuild_labels(out, meta)
    _update_counts(meta)
    _write_json(os.path.join(out, "dataset.json"), meta)
    seconds = time.monotonic() - t0
    if made:
        log("made %d images in %.1f s: %.1f images/s" % (made, seconds, made / seconds))
    log("dataset %s: %d maps, %d samples, %d images" % (out, meta["counts"]["maps"], meta["counts"]["samples"],
                                                         meta["counts"]["images"]))
    return meta


def _update_counts(meta: dict) -> None:
    done = [m for m in meta["maps"].values() if m.get("complete")]
    images = sum(m["images"] for m in done)
    seconds = sum(m["seconds"] for m in done)
    meta["counts"] = {"maps": len(done), "samples": sum(m["samples"] for m in done), "images": images,
                      "seconds": round(seconds, 2)}
    meta["images_per_s"] = round(images / seconds, 2) if seconds else 0.0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m sim4cv.driving_dataset", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="render and label the dataset into --out")
    g.add_argument("--maps", nargs="+", required=True, help="train, val, test and/or map files")
    g.add_argument("--surroundings", default="desert,urban", help="comma-separated: desert, urban")
    g.add_argument("--out", required=True)
    g.add_argument("--views", default="random", choices=dl.VIEW_MODES)
    g.add_argument("--random-views", type=int, default=dl.DEFAULT_RANDOM_VIEWS,
                   help="augmented views per sample with --views random (default %(default)s)")
    g.add_argument("--straight-step", type=float, default=None, help="metres (default 0.8; val/test 2)")
    g.add_argument("--turn-step", type=float, default=None, help="metres (default 0.2; val/test 2)")
    g.add_argument("--max-samples", type=int, default=0, help="lane samples per map at most (0: all)")
    g.add_argument("--seed", type=int, default=0)
    g.add_argument("--conditions", default="", help="weather/time-of-day preset of every image (default clear_noon)")
    g.add_argument("--randomize", type=int, default=0,
                   help="domain randomisation: new conditions (preset, hour, exposure, colours) for every image, "
                        "drawn from this seed (0: off)")
    g.add_argument("--obstacles", type=int, default=0,
                   help="cars parked in the right lane per route, on straights; the labels pass them in the "
                        "left lane (default 0)")
    g.add_argument("--ego-car", action="store_true",
                   help="a car under every view, so its headlights light the road as in closed loop (dusk, night)")
    g.add_argument("--offset-range", type=float, default=dl.RANDOM_OFFSET_M,
                   help="random views shift sideways within +- this many metres (default %(default)s)")
    g.add_argument("--yaw-range", type=float, default=dl.RANDOM_YAW_DEG,
                   help="random views turn within +- this many degrees (default %(default)s)")
    args = parser.parse_args(argv)
    surroundings = [s for s in args.surroundings.split(",") if s]
    for s in surroundings:
        if s not in ("desert", "urban"):
            parser.error("--surroundings %s: desert and/or urban" % s)
    for step in (args.straight_step, args.turn_step):
        if step is not None and step <= 0:
            parser.error("steps must be positive")
    try:
        generate(args.maps, surroundings, args.out, args.views, args.random_views, args.straight_step,
                 args.turn_step, args.max_samples, args.seed, args.conditions, args.randomize,
                 args.obstacles, offset_range=args.offset_range, yaw_range=args.yaw_range, ego_car=args.ego_car)
    except DatasetError as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
