"""Guided driving (docs/driving_guided.md; the paper's "Guided Driving"):
the waypoint network's goal input (-1 left, 0 straight, +1 right) tells the
car which way to go at the next intersection.

    python3 -m sim4cv.driving_guided layout --base BASE.map --seed S --name NAME --out LAYOUT
    python3 -m sim4cv.driving_guided generate --maps train --out DIR [driving_dataset's options]
    python3 -m sim4cv.driving_guided evaluate --model OUT/model.pt --maps test --out DIR
    python3 -m sim4cv.driving_guided evaluate --policy reference --maps test --out DIR
    python3 -m sim4cv.driving_guided probe --model OUT/model.pt --data DIR

* `layout` turns a map of `sim4cv_mapgen` (its roads) into a layout whose
  routes take every turn of every junction (left, straight, right from
  every arm); `sim4cv_mapgen --from LAYOUT` dresses it
  (scenes/driving/guided/generate.sh).
* `generate` is sim4cv.driving_dataset's generator with a goal per lane
  pose: where the route is within GOAL_BEFORE_M before a junction or in
  it, the direction the route takes there; elsewhere a seeded random goal.
* `evaluate` drives the car with a policy from random starts; before each
  junction the client draws a command among the junction's exits (seeded)
  and sets it as the network's goal; the exit the car takes is read from
  its trajectory. guided.json reports the fraction of junctions taken as
  commanded, the deviation from the lane of the road actually taken and
  the lane departures.
* `probe` checks offline whether a model uses its goal (goal_probe).
"""

import argparse
import csv
import json
import math
import os
import sys
import time
import zlib
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import driving_control as dc
from . import driving_dataset as dd
from . import driving_labels as dl
from . import driving_metrics as dm
# The road grid and route goals live in driving_route (the evaluator needs them
# too); the names stay importable from here for existing callers.
from .driving_route import (GOAL, GOAL_BEFORE_M, OPPOSITE, SIDES, GuidedError, MapGoals, RoadGrid,  # noqa: F401
                            RouteGoals, random_goal, route_junctions, side_towards, turn_of)

GUIDED_DIR = os.path.join("scenes", "driving", "guided")
DEFAULT_JUNCTIONS = 8     # junctions per evaluation run
DEFAULT_RUNS = 2          # runs per map
DEFAULT_SPEED = 8.0       # m/s, the controller's speed cap (as sim4cv.driving_eval)
OFF_ROAD_M = 4.0          # farther than this from every lane centre: the car left the road
EGO, EGO_CAMERA = "ego", "ego_cam"



# ---------------------------------------------------------------------------
# Routes through every choice of every junction (the layouts)

def junction_choices(grid: RoadGrid) -> List[Tuple[Tuple[int, int], str, str]]:
    """Every (junction, entry side, exit side) but U-turns, sorted."""
    out = []
    for j in grid.junctions():
        for e in SIDES:
            for x in SIDES:
                if e in grid.conn[j] and x in grid.conn[j] and e != x:
                    out.append((j, e, x))
    return out


def _next_side(grid: RoadGrid, tile, entry: str) -> str:
    """The way on through a tile that is no junction (a straight or a bend)."""
    others = [s for s in grid.conn[tile] if s != entry]
    if len(others) != 1:
        raise GuidedError("tile %s entered through %s has %d ways on" % (tile, entry, len(others)))
    return others[0]


def make_routes(grid: RoadGrid, seed: int, existing: Sequence[Sequence] = (), max_routes: int = 63,
                max_tiles: int = 400) -> List[List[Tuple[int, int]]]:
    """Open routes that together take every choice of every junction at least
    once. A route starts two tiles before the first choice not yet taken
    (random turns on the way back), takes it, then heads for the nearest
    junction arm with a choice not yet taken (breadth-first over (tile,
    entry side)) and takes it, and so on until every choice is taken or the
    route has max_tiles tiles. `existing`: closed routes whose choices count
    as taken."""
    rng = np.random.default_rng(seed)
    taken = {c: 0 for c in junction_choices(grid)}
    for tiles in existing:
        for j in route_junctions(grid, tiles, True):
            taken[(j["tile"], j["entry"], j["exit"])] += 1

    def untaken(tile, entry):
        return sorted(x for x in grid.conn[tile] if x != entry and taken[(tile, entry, x)] == 0)

    def ways(tile, entry):  # exit sides from (tile, entry): every exit of a junction, the one way on elsewhere
        return sorted(x for x in grid.conn[tile] if x != entry) if grid.is_junction(tile) \
            else [_next_side(grid, tile, entry)]

    def path_to_untaken(tile, entry):
        """Exit sides from (tile, entry) to the nearest arm with an untaken choice, and that arm."""
        seen = {(tile, entry): None}
        queue = [(tile, entry)]
        for state in queue:
            if state != (tile, entry) and grid.is_junction(state[0]) and untaken(*state):
                sides = []
                while seen[state] is not None:
                    state, side = seen[state]
                    sides.append(side)
                return list(reversed(sides))
            for side in ways(*state):
                nxt = (grid.neighbour(state[0], side), OPPOSITE[side])
                if nxt not in seen:
                    seen[nxt] = (state, side)
                    queue.append(nxt)
        return None

    routes = []
    while len(routes) < max_routes and any(n == 0 for n in taken.values()):
        j, entry, exit_ = next(c for c, n in taken.items() if n == 0)
        back, tile, side = [j], j, entry
        for _ in range(2):  # two tiles back from the junction
            prev = grid.neighbour(tile, side)
            back.append(prev)
            options = sorted(s_ for s_ in grid.conn[prev] if s_ != OPPOSITE[side])
            side = options[int(rng.integers(len(options)))]
            tile = prev
        tiles = list(reversed(back))
        taken[(j, entry, exit_)] += 1
        tile, side = j, exit_
        while len(tiles) < max_tiles:
            nxt, ent = grid.neighbour(tile, side), OPPOSITE[side]
            tiles.append(nxt)
            tile = nxt
            if grid.is_junction(tile) and untaken(tile, ent):
                options = untaken(tile, ent)
                side = options[int(rng.integers(len(options)))]
                taken[(tile, ent, side)] += 1
                continue
            route = path_to_untaken(tile, ent)
            if route is None:  # every choice taken
                side = None
                break
            side = route[0]
            if grid.is_junction(tile):
                taken[(tile, ent, side)] += 1
        if grid.is_junction(tiles[-1]) and side is not None:  # the choice taken there needs its exit tile
            tiles.append(grid.neighbour(tiles[-1], side))
        while grid.is_junction(tiles[-1]) or len(tiles) < 3:  # end on a plain tile
            ent = side_towards(tiles[-1], tiles[-2])
            tiles.append(grid.neighbour(tiles[-1], ways(tiles[-1], ent)[0]))
        routes.append(tiles)
    missing = [c for c, n in taken.items() if n == 0]
    if missing:
        raise GuidedError("%d junction choices left without a route (max_routes %d)" % (len(missing), max_routes))
    return routes


def read_routes(path: str) -> Dict[str, Tuple[bool, List[Tuple[int, int]]]]:
    return dd.parse_map(path)["routes"]


def write_layout(base: str, out: str, seed: int, name: str, header: Sequence[str] = ()) -> dict:
    """The layout of `base` (a sim4cv_mapgen map): its grid, its closed route
    'loop' and routes g01, g02, ... through every junction choice (make_routes)."""
    with open(base) as f:
        lines = [line.rstrip("\n") for line in f]
    grid = RoadGrid.from_map(base)
    start = next(i for i, line in enumerate(lines) if line.startswith("grid "))
    grid_lines = lines[start:start + grid.height + 2]  # grid, rows, end
    tile_line = next((line for line in lines if line.startswith("tile_size ")), "tile_size 20")
    base_routes = read_routes(base)
    loops = [tiles for closed, tiles in base_routes.values() if closed]
    routes = make_routes(grid, seed, loops)
    text = ["sim4cv-map 1"] + ["# " + h for h in header] + ["name %s" % name, tile_line, "surroundings desert"]
    text += grid_lines
    for rname, (closed, tiles) in base_routes.items():
        text.append("route %s %s" % (rname, "closed" if closed else "open"))
        text += _tiles_lines(tiles)
    for k, tiles in enumerate(routes, 1):
        text.append("route g%02d open" % k)
        text += _tiles_lines(tiles)
    with open(out, "w") as f:
        f.write("\n".join(text) + "\n")
    choices = junction_choices(grid)
    kinds = [len(grid.conn[j]) for j in grid.junctions()]
    return {"junctions": len(kinds), "t_junctions": kinds.count(3), "crossroads": kinds.count(4),
            "choices": len(choices), "routes": len(routes) + len(base_routes),
            "route_tiles": sum(len(r) for r in routes)}


def _tiles_lines(tiles, per_line: int = 12) -> List[str]:
    return ["tiles " + " ".join("%d,%d" % t for t in tiles[i:i + per_line]) for i in range(0, len(tiles), per_line)]


# ---------------------------------------------------------------------------
# Which exit a car takes: its tile from its trajectory

class TileTracker:
    """Follows a car over the road tiles: the tile it is on (off-road tiles
    are ignored: the car stays on the last road tile) and each junction
    passage (entry side, exit side, turn). A car that reaches a road tile
    that does not join the current one is `lost` (it left the road)."""

    def __init__(self, grid: RoadGrid, tile, prev=None):
        self.grid = grid
        self.tile = tuple(tile)
        self.prev = tuple(prev) if prev is not None else None
        self.visited = ([self.prev] if self.prev else []) + [self.tile]
        self.passages: List[dict] = []
        self.open: Optional[dict] = None
        self.lost = False
        if grid.is_junction(self.tile) and self.prev is not None:
            self._enter_junction(self.tile, side_towards(self.tile, self.prev))

    def _enter_junction(self, tile, entry):
        self.open = {"tile": tile, "entry": entry, "exit": None, "turn": None}

    def update(self, x: float, y: float) -> Optional[Tuple]:
        """Feeds one position; returns (new tile, old tile) when the car entered another road tile."""
        if self.lost:
            return None
        t = self.grid.tile_at(x, y)
        if t == self.tile or not self.grid.is_road(t):
            return None
        old = self.tile
        side = side_towards(old, t)
        if self.open is not None:  # leaving a junction
            if side is not None and side in self.grid.conn[old]:
                self.open.update(exit=side, turn=turn_of(self.open["entry"], side))
            self.passages.append(self.open)
            self.open = None
        if side is None or side not in self.grid.conn[old]:
            self.lost = True
            return None
        self.prev, self.tile = old, t
        self.visited.append(t)
        if self.grid.is_junction(t):
            self._enter_junction(t, OPPOSITE[side])
        return t, old

    def finish(self) -> List[dict]:
        """Closes an unfinished passage (exit None) and returns every passage."""
        if self.open is not None:
            self.passages.append(self.open)
            self.open = None
        return self.passages


def junction_passages(grid: RoadGrid, points: Sequence[Tuple[float, float]], prev=None) -> List[dict]:
    """The junction passages of a trajectory [(x, y), ...]: [{tile, entry, exit, turn}],
    exit and turn None where the trajectory ends in the junction or leaves the road there."""
    tracker = TileTracker(grid, grid.tile_at(*points[0]), prev)
    for x, y in points[1:]:
        tracker.update(x, y)
    return tracker.finish()


# ---------------------------------------------------------------------------
# The navigator: commands before each junction, the planned path

class Navigator:
    """Plans the car's way tile by tile from where it is: at each junction
    ahead a command drawn at random among its exits (no U-turns) from `rng`,
    drawn when the junction comes within `ahead` tiles. goal() is the
    command of the next junction (or of the one the car is in)."""

    def __init__(self, grid: RoadGrid, rng, prev, tile, ahead: int = 4):
        self.grid, self.rng, self.ahead = grid, rng, ahead
        self.tracker = TileTracker(grid, tile, prev)
        self.plan = [(tuple(prev), None), (tuple(tile), None)]  # (tile, command at it); plan[1] = current
        self.records: List[dict] = []
        self.current_command = None  # the command of the junction the car is in
        if grid.is_junction(tuple(tile)):
            self.plan[1] = (tuple(tile), self._draw(tuple(tile), side_towards(tuple(tile), tuple(prev))))
        self._extend()

    def _draw(self, tile, entry) -> str:
        options = sorted(self.grid.exits(tile, entry), key=lambda t: GOAL[t])
        return options[int(self.rng.integers(len(options)))]

    def _extend(self):
        while len(self.plan) < self.ahead + 2 or not any(c for _, c in self.plan[1:]):
            (a, _), (b, cmd) = self.plan[-2], self.plan[-1]
            entry = side_towards(b, a)
            side = self.grid.exits(b, entry)[cmd] if cmd else _next_side(self.grid, b, entry)
            c = self.grid.neighbour(b, side)
            ccmd = self._draw(c, OPPOSITE[side]) if self.grid.is_junction(c) else None
            self.plan.append((c, ccmd))
            if len(self.plan) > 200:
                raise GuidedError("no junction ahead of tile %s" % (b,))

    def update(self, x: float, y: float) -> None:
        moved = self.tracker.update(x, y)
        if moved is None:
            return
        new, old = moved
        left_junction = self.grid.is_junction(old)
        if left_junction:
            passage = self.tracker.passages[-1]
            passage["commanded"] = self.plan[1][1]
            passage["ok"] = passage["turn"] == passage["commanded"]
            self.records.append(passage)
        if self.plan[1][0] == old and self.plan[2][0] == new:  # as planned
            self.plan.pop(0)
        else:  # the car went another way: plan again from where it is
            cmd = self._draw(new, side_towards(new, old)) if self.grid.is_junction(new) else None
            self.plan = [(old, None), (new, cmd)]
        self._extend()

    @property
    def lost(self) -> bool:
        return self.tracker.lost

    def goal(self) -> int:
        """The command of the junction the car is in or comes to next, as the network's goal."""
        return next(GOAL[c] for _, c in self.plan[1:] if c)

    def planned_tiles(self) -> List[Tuple[int, int]]:
        return [t for t, _ in self.plan]

    def finish(self) -> List[dict]:
        """Every junction passage, an unfinished one (still in the junction) left out."""
        return self.records


class GuidedReferencePolicy:
    """The true waypoints of the planned way (the commanded exits), 2 to 8 m
    ahead of the car's nearest point on it: checks the harness."""
    name = "reference"
    goal = 0.0

    def waypoints(self, rgb, pose, nav: Navigator) -> List[float]:
        x, y, yaw = pose
        tiles = nav.planned_tiles()
        path = dd.RoutePath(nav.grid.map_info(tiles), "path")
        progress = dm.Progress(path, 0.0)
        progress.update(x, y)
        points = [path.point(progress.u + dd.WAYPOINT_STEP_M * k)[:2] for k in range(1, dd.WAYPOINT_COUNT + 1)]
        return [c for vh in dl.encode(x, y, yaw, points) for c in vh]


class GuidedNetworkPolicy:
    """driving_eval.NetworkPolicy with its goal set to the navigator's command before every frame."""
    name = "network"

    def __init__(self, path: str):
        from .driving_eval import NetworkPolicy
        self.net = NetworkPolicy(path)
        self.path = path

    def waypoints(self, rgb, pose, nav: Navigator) -> List[float]:
        self.net.goal = float(nav.goal())
        return self.net.waypoints(rgb, pose, None)


# ---------------------------------------------------------------------------
# Closed-loop guided evaluation

def start_poses(grid: RoadGrid, rng, count: int) -> List[Tuple[Tuple[int, int], Tuple[int, int]]]:
    """`count` random (previous tile, start tile): start tiles are straights
    whose previous and next tiles are no junctions, the direction random."""
    straights = []
    for t in sorted(grid.conn, key=lambda t: (t[1], t[0])):
        sides = grid.conn[t]
        if len(sides) == 2 and OPPOSITE[next(iter(sides))] in sides:
            if not any(grid.is_junction(grid.neighbour(t, s)) for s in sides):
                straights.append(t)
    if not straights:
        raise GuidedError("no straight to start from")
    out = []
    for _ in range(count):
        t = straights[int(rng.integers(len(straights)))]
        sides = sorted(grid.conn[t])
        entry = sides[int(rng.integers(2))]
        out.append((grid.neighbour(t, entry), t))
    return out


def driven_deviation(grid: RoadGrid, visited: Sequence, points: Sequence[Tuple[float, float]]) -> Optional[List[float]]:
    """The signed deviation (m, + right) of each point from the right-lane
    centre of the tiles actually driven (`visited`, consecutive road tiles),
    exact (RoutePath); None if those tiles do not make a path."""
    tiles = list(visited)
    if len(tiles) < 2:
        return None
    last, before = tiles[-1], tiles[-2]
    entry = side_towards(last, before)
    on = [s for s in sorted(grid.conn[last]) if s != entry]
    tiles.append(grid.neighbour(last, on[0] if len(on) == 1 or OPPOSITE[entry] not in on else OPPOSITE[entry]))
    try:
        path = dd.RoutePath(grid.map_info(tiles), "path")
    except dd.DatasetError:
        return None
    progress = dm.Progress(path, 0.0)
    return [progress.update(x, y) for x, y in points]


def drive_guided(client, grid: RoadGrid, info: dict, policy, rng, start, junctions: int = DEFAULT_JUNCTIONS,
                 speed: float = DEFAULT_SPEED, frame_hz: float = 30.0, max_seconds: Optional[float] = None,
                 render: bool = True, log=print) -> Tuple[dict, list]:
    """One run from `start` (previous tile, start tile) until `junctions`
    junction passages, the car leaving the road, or a time limit."""
    from .driving_eval import car_pose
    prev, tile = start
    nav = Navigator(grid, rng, prev, tile)
    first = dd.RoutePath(grid.map_info(nav.planned_tiles()), "path")
    x0, y0, yaw0 = first.point(grid.tile_size / 2.0)
    ego = client.spawn("car", EGO, x0, y0, 0.0, math.degrees(yaw0))
    cam = dd.CAMERA_SETTINGS  # without `render` (the reference policy needs no image) a tiny one
    client.add_camera(EGO_CAMERA, mounted_on=EGO, width=cam["width"] if render else 32,
                      height=cam["height"] if render else 18, fov_y_deg=cam["fov_y_deg"],
                      pitch_down_deg=cam["pitch_down_deg"], offset=(cam["forward_m"], 0.0, cam["above_body_m"]))
    client.subscribe(EGO_CAMERA, ["rgb"], "lockstep", with_state=True)
    collisions = dm.Collisions(info["objects"])
    limit_s = max_seconds if max_seconds else junctions * 4.0 * grid.tile_size / (speed / 2.0) + 30.0
    rows, points, road_devs = [], [], []
    reason = "time_limit"
    frame = client.step_and_receive(timeout=30.0)
    t0 = frame.sim_time
    infer_s = 0.0
    while True:
        x, y, yaw, car_speed = car_pose(frame, ego)
        nav.update(x, y)
        road = client.query_road(x, y, heading_deg=math.degrees(yaw))
        road_dev = -road.lateral_offset if road.distance <= OFF_ROAD_M else math.copysign(road.distance,
                                                                                           -road.lateral_offset)
        hit = collisions.update(x, y, yaw)
        points.append((x, y))
        road_devs.append(road_dev)
        t = frame.sim_time - t0
        done = None
        if len(nav.records) >= junctions:
            done = "junctions"
        elif nav.lost or road.distance > OFF_ROAD_M:
            done = "left_road"
        elif t > limit_s:
            done = "time_limit"
        goal = nav.goal()
        row = [round(t, 4), round(x, 3), round(y, 3), round(math.degrees(yaw), 2), "%d,%d" % nav.tracker.tile,
               goal, round(road_dev, 4), round(car_speed, 3)]
        if done:
            rows.append(row + ["", "", "", hit])
            reason = done
            break
        started = time.perf_counter()
        w = policy.waypoints(frame.image("rgb") if render else None, (x, y, yaw), nav)
        infer_s += time.perf_counter() - started
        steering, throttle, brake = dc.controls_from_waypoints(w, speed=car_speed, max_speed=speed)
        client.send_controls(ego, steering, throttle, brake)
        rows.append(row + [round(steering, 4), round(throttle, 4), round(brake, 4), hit])
        frame = client.step_and_receive(timeout=30.0)
    passages = list(nav.records)
    if reason == "left_road" and nav.tracker.open is not None:  # left the road in a junction: a failed passage
        failed = dict(nav.tracker.open, commanded=nav.plan[1][1], ok=False)
        passages.append(failed)
    driven = driven_deviation(grid, nav.tracker.visited, points)
    devs = driven if driven is not None else road_devs
    for r, d in zip(rows, devs):
        r.insert(7, round(d, 4))
    distance = sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:]))
    run = dm.score(devs, distance, collisions.count)
    run["query_road"] = {k: v for k, v in dm.score(road_devs).items() if k not in ("distance_m", "collisions")}
    run.update(start={"prev": list(prev), "tile": list(tile)}, reason=reason, completed=reason == "junctions",
               passages=[{"tile": list(p["tile"]), "entry": p["entry"], "exit": p["exit"], "taken": p["turn"],
                          "commanded": p["commanded"], "ok": bool(p["ok"])} for p in passages],
               junctions=len(passages), as_commanded=sum(1 for p in passages if p["ok"]),
               sim_seconds=round(rows[-1][0], 3), policy_ms=round(1000.0 * infer_s / max(len(rows), 1), 3),
               deviation_from="driven_tiles" if driven is not None else "query_road")
    log("  run from %s: %s, %d/%d junctions as commanded, %.0f m, mean deviation %.1f cm, departures %d"
        % (tile, reason, run["as_commanded"], run["junctions"], run["distance_m"], run["mean_deviation_cm"] or 0.0,
           run["lane_departures"]))
    return run, rows


ROW_COLUMNS = ["t", "x", "y", "yaw_deg", "tile", "goal", "query_road_deviation_m", "deviation_m", "speed",
               "steering", "throttle", "brake", "collision"]


def _summary(runs: Sequence[dict], devs: Sequence[Sequence[float]]) -> dict:
    out = dm.pooled(runs, devs)
    passages = [p for r in runs for p in r["passages"]]
    out["junctions"] = len(passages)
    out["as_commanded"] = sum(1 for p in passages if p["ok"])
    out["fraction_as_commanded"] = round(out["as_commanded"] / len(passages), 4) if passages else None
    out["by_command"] = {}
    for turn in ("left", "straight", "right"):
        these = [p for p in passages if p["commanded"] == turn]
        out["by_command"][turn] = {"junctions": len(these), "as_commanded": sum(1 for p in these if p["ok"])}
    out["left_road"] = sum(1 for r in runs if r["reason"] == "left_road")
    return out


def evaluate(policy, maps: Sequence[str], surroundings: Sequence[str], out: str, runs: int = DEFAULT_RUNS,
             junctions: int = DEFAULT_JUNCTIONS, seed: int = 0, speed: float = DEFAULT_SPEED,
             frame_hz: float = 30.0, conditions: str = "", log=print) -> dict:
    """Drives `runs` runs of `junctions` junctions on every map; writes
    out/guided.json and out/runs/<map>_<k>.csv; returns guided.json's content."""
    import sim4cv
    from .daemon import OwnDaemon

    resolved = resolve_maps(maps, surroundings)
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    report = {"settings": {"policy": policy.name, "model": getattr(policy, "path", None),
                           "maps": [p for p, _ in resolved], "runs_per_map": runs, "junctions_per_run": junctions,
                           "seed": seed, "speed_m_s": speed, "frame_hz": frame_hz,
                           "conditions": conditions or "clear_noon", "off_road_m": OFF_ROAD_M,
                           "lane_departure_m": dm.LANE_DEPARTURE_M},
              "maps": {}}
    pooled = {"overall": [], "desert": [], "urban": []}
    t_start = time.monotonic()
    render = policy.name != "reference"
    for path, _ in resolved:
        info = dd.parse_map(path)
        grid = RoadGrid.from_map(path)
        name = info["name"]
        log("%s (%s)" % (name, info["surroundings"]))
        rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
        flags = ["--map", path, "--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0",
                 "--frame-hz", str(int(frame_hz))]
        if conditions:
            flags += ["--conditions", conditions]
        map_runs, map_devs = [], []
        for k, start in enumerate(start_poses(grid, rng, runs)):
            for attempt in (1, 2):  # a daemon lost under the run (killed from outside): the run once more
                run_rng = np.random.default_rng([seed, zlib.crc32(name.encode()), k])  # the run's commands
                try:
                    with OwnDaemon(flags, mode="lockstep") as daemon, \
                            sim4cv.connect(daemon.address, name="driving_guided", timeout=30.0) as client:
                        for entity in client.get_world().entities:
                            if entity.name in ("car", "uav"):
                                client.remove(entity.id)
                        run, rows = drive_guided(client, grid, info, policy, run_rng, start, junctions, speed,
                                                 frame_hz, render=render, log=log)
                    break
                except ConnectionError as err:
                    if attempt == 2:
                        raise
                    log("  run %d: the daemon went away (%s); running it again" % (k, err))
            with open(os.path.join(out, "runs", "%s_%d.csv" % (name, k)), "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(ROW_COLUMNS)
                w.writerows(rows)
            devs = [r[7] for r in rows]
            map_runs.append(run)
            map_devs.append(devs)
            for key in ("overall", info["surroundings"]):
                if key in pooled:
                    pooled[key].append((run, devs))
        report["maps"][name] = {"surroundings": info["surroundings"], "runs": map_runs,
                                "score": _summary(map_runs, map_devs)}
    for key, entries in pooled.items():
        if entries:
            report[key if key == "overall" else "surroundings_" + key] = _summary(
                [r for r, _ in entries], [d for _, d in entries])
    report["seconds"] = round(time.monotonic() - t_start, 1)
    with open(os.path.join(out, "guided.json"), "w") as f:
        json.dump(report, f, indent=1)
    o = report.get("overall", {})
    log("overall: %s/%s junctions as commanded (%s), mean deviation %s cm, within 25 cm %s, departures %s, "
        "left the road %s of %s runs (%.0f s)"
        % (o.get("as_commanded"), o.get("junctions"), o.get("fraction_as_commanded"), o.get("mean_deviation_cm"),
           o.get("within_25cm"), o.get("lane_departures"), o.get("left_road"), o.get("runs"), report["seconds"]))
    return report


# ---------------------------------------------------------------------------
# The dataset

def resolve_maps(specs: Sequence[str], surroundings: Sequence[str]):
    """train|test (scenes/driving/guided/<set>) or map files."""
    from .daemon import REPO_ROOT
    return dd.resolve_maps(specs, surroundings, os.path.join(REPO_ROOT, GUIDED_DIR))


def generate(maps: Sequence[str], surroundings: Sequence[str], out: str, views: str = "random",
             random_views: int = dl.DEFAULT_RANDOM_VIEWS, straight_step: Optional[float] = None,
             turn_step: Optional[float] = None, max_samples: int = 0, seed: int = 0,
             before_m: float = GOAL_BEFORE_M, log=print, offset_range: float = dl.RANDOM_OFFSET_M,
             yaw_range: float = dl.RANDOM_YAW_DEG, randomize: int = 0, ego_car: bool = False) -> dict:
    """driving_dataset.generate on the guided maps with a goal per lane pose
    (MapGoals); resumes and refuses a DIR of other settings the same way.
    randomize, ego_car: driving_dataset.generate's (new conditions for every
    image; a car under every view)."""
    from .daemon import REPO_ROOT
    guided = {"goal_before_m": before_m, "goal_elsewhere": "random, seeded (crc32 of seed/map/route/u)"}
    return dd.generate(maps, surroundings, out, views, random_views, straight_step, turn_step, max_samples, seed,
                       log=log, scenes_dir=os.path.join(REPO_ROOT, GUIDED_DIR),
                       goals=lambda path: MapGoals(path, seed, before_m), extra_settings={"guided": guided},
                       offset_range=offset_range, yaw_range=yaw_range, randomize=randomize, ego_car=ego_car)


# ---------------------------------------------------------------------------
# Does a model use its goal? (offline, on a dataset of `generate`)

def dataset_junction_rows(folder: str) -> List[dict]:
    """labels.csv's rows with `junction` (the turn there, or None away from
    junctions) and `u`: the lane poses are re-enumerated as generate_map
    makes them (routes in map-file order, lane_samples, max_samples)."""
    with open(os.path.join(folder, "dataset.json")) as f:
        meta = json.load(f)
    settings = meta["settings"]
    where = {}
    for name, m in meta["maps"].items():
        if not m.get("complete"):
            continue
        info = dd.parse_map(m["path"])
        goals = MapGoals(m["path"], settings["seed"], settings.get("guided", {}).get("goal_before_m", GOAL_BEFORE_M))
        sample = 0
        for route in info["routes"]:
            lane = dd.RoutePath(info, route)
            for u in dd.lane_samples(lane, m["straight_step"], m["turn_step"]):
                if settings["max_samples"] and sample >= settings["max_samples"]:
                    break
                hit = goals.routes[route].junction_at(u)
                where[(name, sample)] = (route, u, hit[1] if hit else None)
                sample += 1
    with open(os.path.join(folder, "labels.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        route, u, turn = where[(r["map"], int(r["sample"]))]
        if route != r["route"]:
            raise GuidedError("%s: row %s does not match the re-enumerated lane poses" % (folder, r["image"]))
        r["u"], r["junction"] = u, turn
    return rows


def goal_probe(model_path: str, folder: str, max_rows: int = 0, log=print) -> dict:
    """The model's error on the junction rows of a dataset with the true goal
    and with each other goal (a model that uses its goal errs much more with
    a wrong one), and how far the goal moves its waypoints there and away
    from junctions (where it should not)."""
    import cv2
    import torch
    from .driving_train import TARGETS, load_model
    model = load_model(model_path)
    if not model.use_goal:
        raise GuidedError("%s has no goal input (train it with --goal)" % model_path)
    torch.set_grad_enabled(False)
    rows = dataset_junction_rows(folder)
    if max_rows:
        rows = rows[:max_rows]
    stats = {"junction": {"rows": 0, "mse_true_goal": 0.0, "mse_wrong_goal": 0.0, "h4_spread_m": 0.0},
             "elsewhere": {"rows": 0, "h4_spread_m": 0.0}}
    batch = []

    def flush():
        images = torch.stack([b[0] for b in batch])
        outs = {g: model(images, torch.full((len(batch), 1), float(g))).numpy() for g in (-1, 0, 1)}
        for k, (_, r) in enumerate(batch):
            target = np.array([float(r[c]) for c in TARGETS])
            spread = max(o[k][7] for o in outs.values()) - min(o[k][7] for o in outs.values())
            if r["junction"] is None:
                stats["elsewhere"]["rows"] += 1
                stats["elsewhere"]["h4_spread_m"] += spread
                continue
            g = GOAL[r["junction"]]
            s = stats["junction"]
            s["rows"] += 1
            s["mse_true_goal"] += float(np.mean((outs[g][k] - target) ** 2))
            s["mse_wrong_goal"] += float(np.mean([np.mean((outs[w][k] - target) ** 2) for w in (-1, 0, 1) if w != g]))
            s["h4_spread_m"] += spread
        batch.clear()

    for r in rows:
        img = cv2.imread(os.path.join(folder, r["image"]), cv2.IMREAD_COLOR)
        img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        if img.shape[:2] != (model.height, model.width):
            img = cv2.resize(img, (model.width, model.height), interpolation=cv2.INTER_AREA)
        batch.append((torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1))).float(), r))
        if len(batch) == 64:
            flush()
    if batch:
        flush()
    for s in stats.values():
        n = max(s["rows"], 1)
        for k in list(s):
            if k != "rows":
                s[k] = round(s[k] / n, 5)
    log(json.dumps(stats, indent=1))
    return stats


# ---------------------------------------------------------------------------
# Command line

def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving_guided", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    lay = sub.add_parser("layout", help="routes through every junction choice of a sim4cv_mapgen map")
    lay.add_argument("--base", required=True, help="a map of sim4cv_mapgen (its grid and loop)")
    lay.add_argument("--seed", type=int, required=True, help="seed of the routes")
    lay.add_argument("--name", required=True)
    lay.add_argument("--out", required=True)
    lay.add_argument("--comment", action="append", default=[], help="a header comment line (repeatable)")

    g = sub.add_parser("generate", help="the labelled dataset with goals into --out")
    g.add_argument("--maps", nargs="+", required=True, help="train, test (scenes/driving/guided) and/or map files")
    g.add_argument("--surroundings", default="desert,urban")
    g.add_argument("--out", required=True)
    g.add_argument("--views", default="random", choices=dl.VIEW_MODES)
    g.add_argument("--random-views", type=int, default=dl.DEFAULT_RANDOM_VIEWS)
    g.add_argument("--straight-step", type=float, default=None)
    g.add_argument("--turn-step", type=float, default=None)
    g.add_argument("--max-samples", type=int, default=0)
    g.add_argument("--seed", type=int, default=0)
    g.add_argument("--goal-before", type=float, default=GOAL_BEFORE_M,
                   help="metres before a junction from which the goal is its direction (default %(default)s)")
    g.add_argument("--offset-range", type=float, default=dl.RANDOM_OFFSET_M)
    g.add_argument("--yaw-range", type=float, default=dl.RANDOM_YAW_DEG)
    g.add_argument("--randomize", type=int, default=0,
                   help="domain randomisation: new conditions for every image, drawn from this seed (0: off)")
    g.add_argument("--ego-car", action="store_true", help="a car under every view (its headlights, as in closed loop)")

    e = sub.add_parser("evaluate", help="closed-loop guided driving into --out/guided.json")
    e.add_argument("--model", help="OUT/model.pt or OUT/model.onnx of a --goal model (policy network)")
    e.add_argument("--policy", default="network", choices=("network", "reference"))
    e.add_argument("--maps", nargs="+", default=["test"])
    e.add_argument("--surroundings", default="desert,urban")
    e.add_argument("--out", required=True)
    e.add_argument("--runs", type=int, default=DEFAULT_RUNS, help="runs per map (random starts)")
    e.add_argument("--junctions", type=int, default=DEFAULT_JUNCTIONS, help="junctions per run")
    e.add_argument("--seed", type=int, default=0)
    e.add_argument("--speed", type=float, default=DEFAULT_SPEED)
    e.add_argument("--frame-hz", type=float, default=30.0)
    e.add_argument("--conditions", default="")
    e.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    pr = sub.add_parser("probe", help="does a --goal model use its goal? (offline, on a dataset of generate)")
    pr.add_argument("--model", required=True, help="OUT/model.pt")
    pr.add_argument("--data", required=True, help="a dataset folder of generate")
    pr.add_argument("--max-rows", type=int, default=0)
    pr.add_argument("--threads", type=int, default=1)
    a = p.parse_args(argv)
    try:
        if a.command == "probe":
            import torch
            torch.set_num_threads(a.threads)
            goal_probe(a.model, a.data, a.max_rows)
            return 0
        if a.command == "layout":
            stats = write_layout(a.base, a.out, a.seed, a.name, a.comment)
            print("%s: %s" % (a.out, json.dumps(stats, sort_keys=True)))
            return 0
        surroundings = [s for s in a.surroundings.split(",") if s]
        if a.command == "generate":
            generate(a.maps, surroundings, a.out, a.views, a.random_views, a.straight_step, a.turn_step,
                     a.max_samples, a.seed, a.goal_before, offset_range=a.offset_range, yaw_range=a.yaw_range,
                     randomize=a.randomize, ego_car=a.ego_car)
            return 0
        if a.policy == "reference":
            policy = GuidedReferencePolicy()
        else:
            if not a.model:
                p.error("--model is needed with --policy network")
            if a.threads > 0:
                try:
                    import torch
                    torch.set_num_threads(a.threads)
                except ImportError:
                    pass
            policy = GuidedNetworkPolicy(a.model)
        evaluate(policy, a.maps, surroundings, a.out, a.runs, a.junctions, a.seed, a.speed, a.frame_hz,
                 a.conditions)
    except (GuidedError, dd.DatasetError) as err:
        print("error: %s" % err, file=sys.stderr)
        return 2
    except Exception as err:  # noqa: BLE001 - driving_eval's EvalError (bad model files) and the like
        if type(err).__name__ == "EvalError":
            print("error: %s" % err, file=sys.stderr)
            return 2
        raise
    return 0


if __name__ == "__main__":
    sys.exit(main())
