"""A map's road grid and the goals of its routes (docs/driving_guided.md):
which sides of each tile connect, the junctions a route passes and the turn
it takes at each, and the goal input (-1 left, 0 straight, +1 right) of
every lane pose. The geometry both the guided-driving tools
(sim4cv.driving_guided) and the evaluator (sim4cv.driving_eval) use.
"""

import math
import zlib
from typing import Dict, List, Optional, Sequence, Tuple

from . import driving_dataset as dd

SIDES = ("N", "E", "S", "W")
BIT = {"N": 1, "E": 2, "S": 4, "W": 8}
STEP = {"N": (0, -1), "E": (1, 0), "S": (0, 1), "W": (-1, 0)}  # rows grow southwards
OPPOSITE = {"N": "S", "S": "N", "E": "W", "W": "E"}
CLOCKWISE = {"N": "E", "E": "S", "S": "W", "W": "N"}
COUNTER_CLOCKWISE = {v: k for k, v in CLOCKWISE.items()}
GOAL = {"left": -1, "straight": 0, "right": 1}
TURN_OF_GOAL = {v: k for k, v in GOAL.items()}
GOAL_BEFORE_M = 20.0      # the goal is the junction's direction from this far before it until through it


class GuidedError(RuntimeError):
    """Guided driving cannot go on; the message says why."""


# ---------------------------------------------------------------------------
# The road grid of a map: which sides of each tile connect (docs/maps.md)

class RoadGrid:
    """A map's road tiles and their connections: conn[(col, row)] = set of sides."""

    def __init__(self, width: int, height: int, tile_size: float, conn: Dict[Tuple[int, int], frozenset]):
        self.width, self.height, self.tile_size, self.conn = width, height, tile_size, conn

    @classmethod
    def from_rows(cls, rows: Sequence[str], tile_size: float = 20.0) -> "RoadGrid":
        height, width = len(rows), len(rows[0])
        masks = {}
        for r, row in enumerate(rows):
            if len(row) != width:
                raise GuidedError("grid row %d has %d tiles, expected %d" % (r, len(row), width))
            for c, ch in enumerate(row):
                if ch == ".":
                    continue
                masks[(c, r)] = None if ch == "#" else int(ch, 16)

        def offers(tile, side):  # does road tile `tile` connect towards `side` (if its neighbour connects back)?
            if tile not in masks:
                return False
            return masks[tile] is None or bool(masks[tile] & BIT[side])

        conn = {}
        for tile in masks:
            sides = set()
            for side in SIDES:
                nb = (tile[0] + STEP[side][0], tile[1] + STEP[side][1])
                if offers(tile, side) and nb in masks and offers(nb, OPPOSITE[side]):
                    sides.add(side)
            conn[tile] = frozenset(sides)
        return cls(width, height, tile_size, conn)

    @classmethod
    def from_map(cls, path: str) -> "RoadGrid":
        info = dd.parse_map(path)
        return cls.from_rows(info["rows"], info["tile_size"])

    def is_road(self, tile) -> bool:
        return tile in self.conn

    def is_junction(self, tile) -> bool:
        return len(self.conn.get(tile, ())) >= 3

    def junctions(self) -> List[Tuple[int, int]]:
        return sorted((t for t in self.conn if self.is_junction(t)), key=lambda t: (t[1], t[0]))

    def neighbour(self, tile, side):
        return tile[0] + STEP[side][0], tile[1] + STEP[side][1]

    def tile_at(self, x: float, y: float) -> Tuple[int, int]:
        """The (col, row) holding world point (x, y) (it may be off the grid)."""
        t = self.tile_size
        return int(math.floor(x / t + self.width / 2.0)), int(math.floor(self.height / 2.0 - y / t))

    def centre(self, tile) -> Tuple[float, float]:
        t = self.tile_size
        return (tile[0] + 0.5 - self.width / 2.0) * t, (self.height / 2.0 - tile[1] - 0.5) * t

    def exits(self, tile, entry: str) -> Dict[str, str]:
        """{turn: exit side} of a junction entered through `entry` (no U-turns)."""
        return {turn_of(entry, x): x for x in self.conn[tile] if x != entry}

    def map_info(self, tiles: Sequence[Tuple[int, int]], closed: bool = False) -> dict:
        """A parse_map-like dict with one route 'path' through `tiles` (for RoutePath)."""
        return {"tile_size": self.tile_size, "grid": (self.width, self.height),
                "routes": {"path": (closed, list(tiles))}}


def side_towards(a, b) -> Optional[str]:
    """The side of tile a that faces its 4-neighbour b (None if b is no neighbour)."""
    for side, (dc_, dr) in STEP.items():
        if (a[0] + dc_, a[1] + dr) == tuple(b):
            return side
    return None


def turn_of(entry: str, exit_: str) -> str:
    """'left', 'straight', 'right' or 'uturn' for a tile entered through side
    `entry` and left through side `exit_` (right-hand traffic, seen from above)."""
    heading = OPPOSITE[entry]  # entering through the south side means driving north
    if exit_ == heading:
        return "straight"
    if exit_ == CLOCKWISE[heading]:
        return "right"
    if exit_ == COUNTER_CLOCKWISE[heading]:
        return "left"
    return "uturn"


def route_junctions(grid: RoadGrid, tiles: Sequence, closed: bool) -> List[dict]:
    """The junctions a route passes: [{index, tile, entry, exit, turn, goal}],
    index into `tiles` (the open route's first and last tiles only give directions)."""
    n = len(tiles)
    out = []
    for i in (range(n) if closed else range(1, n - 1)):
        tile = tuple(tiles[i])
        if not grid.is_junction(tile):
            continue
        entry, exit_ = side_towards(tile, tiles[(i - 1) % n]), side_towards(tile, tiles[(i + 1) % n])
        turn = turn_of(entry, exit_)
        out.append({"index": i, "tile": tile, "entry": entry, "exit": exit_, "turn": turn, "goal": GOAL.get(turn)})
    return out


# ---------------------------------------------------------------------------
# Goals of a route's lane poses (the dataset)

def random_goal(seed: int, map_name: str, route: str, u: float) -> int:
    """The seeded random goal of the lane pose at arc length u (away from junctions)."""
    key = "%d/%s/%s/%d" % (seed, map_name, route, int(round(u * 1000.0)))
    return zlib.crc32(key.encode()) % 3 - 1


class RouteGoals:
    """goal(u): within `before_m` before a junction of the route until its
    end, the direction the route takes there; elsewhere random_goal."""

    def __init__(self, info: dict, grid: RoadGrid, route: str, seed: int = 0, before_m: float = GOAL_BEFORE_M):
        closed, tiles = info["routes"][route]
        self.path = dd.RoutePath(info, route)
        self.closed, self.seed, self.map_name, self.route = closed, seed, info["name"], route
        first = 0 if closed else 1  # RoutePath's segment k is tile k (closed) or k + 1 (open)
        self.intervals = []  # (start_u, end_u, goal, turn, tile)
        for j in route_junctions(grid, tiles, closed):
            start, length = self.path.segments[j["index"] - first][:2]
            self.intervals.append((start - before_m, start + length, j["goal"], j["turn"], j["tile"]))

    def junction_at(self, u: float):
        """(goal, turn, tile) of the junction whose goal region holds u, or None."""
        us = [u]
        if self.closed:
            u %= self.path.length
            us = [u, u + self.path.length, u - self.path.length]
        for start, end, goal, turn, tile in self.intervals:
            if any(start <= v <= end for v in us):
                return goal, turn, tile
        return None

    def goal(self, u: float) -> int:
        hit = self.junction_at(u)
        return hit[0] if hit is not None else random_goal(self.seed, self.map_name, self.route, u)


class MapGoals:
    """goal_fn(route, u, sample) for driving_dataset.generate_map."""

    def __init__(self, path: str, seed: int = 0, before_m: float = GOAL_BEFORE_M):
        info = dd.parse_map(path)
        grid = RoadGrid.from_map(path)
        self.routes = {r: RouteGoals(info, grid, r, seed, before_m) for r in info["routes"]}
        self.counts = {"junction": 0, "random": 0, -1: 0, 0: 0, 1: 0}

    def summary(self) -> dict:
        """The counts for dataset.json: lane poses at junctions and away, and per goal."""
        c = self.counts
        return {"junction": c["junction"], "random": c["random"], "left": c[-1], "straight": c[0], "right": c[1]}

    def __call__(self, route: str, u: float, sample: int = 0) -> int:
        goals = self.routes[route]
        hit = goals.junction_at(u)
        goal = hit[0] if hit is not None else random_goal(goals.seed, goals.map_name, route, u)
        self.counts["junction" if hit is not None else "random"] += 1
        self.counts[goal] += 1
        return goal
