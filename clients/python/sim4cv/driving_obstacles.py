"""Obstacles on the road for the driving case study (docs/driving.md,
"Obstacles"): cars parked in the right lane on straights, and the ideal
path that passes them in the left lane.

The ideal path leaves the right lane RAMP_M before an obstacle, is in the
left lane (LANE_SHIFT_M to the left) from HOLD_M before it to HOLD_M after
it, and comes back over RAMP_M; the ramps are smoothsteps, so the path's
heading changes smoothly. Obstacles are placed only where the road is
straight from CLEAR_M before to CLEAR_M after them (the whole manoeuvre
happens on a straight), at least SPACING_M apart, at positions drawn from
a seed and the map's name (the dataset and the evaluation place the same
obstacles).
"""

import math
import zlib
from typing import List, Sequence, Tuple

import numpy as np

LANE_SHIFT_M = 4.0   # right-lane centre to left-lane centre
HOLD_M = 10.0        # in the left lane from this far before the obstacle to this far after it
RAMP_M = 18.0        # length of each lane change
CLEAR_M = HOLD_M + RAMP_M + 2.0
SPACING_M = 2 * CLEAR_M + 20.0
OBSTACLE_NAME = "obstacle_%d"
# a car's footprint (sim4cvd's car: a 4.5 x 1.8 m chassis box), half length and half width
CAR_HALF_LENGTH_M, CAR_HALF_WIDTH_M = 2.25, 0.9


def cars_overlap(a: Tuple[float, float, float], b: Tuple[float, float, float], margin: float = 0.0) -> bool:
    """Whether two cars at poses (x, y, yaw radians) overlap, each footprint
    grown by `margin` on every side: a separating axis test on the two
    rectangles (no axis of either separates them)."""
    half = (CAR_HALF_LENGTH_M + margin, CAR_HALF_WIDTH_M + margin)
    dx, dy = b[0] - a[0], b[1] - a[1]
    axes = [(math.cos(yaw), math.sin(yaw)) for yaw in (a[2], b[2])]
    for ax, ay in axes + [(-s, c) for c, s in axes]:
        # both rectangles' extents along the axis: each one's length and width projected on it
        reach = sum(half[0] * abs(ax * c + ay * s) + half[1] * abs(-ax * s + ay * c) for c, s in axes)
        if abs(dx * ax + dy * ay) > reach:
            return False
    return True


def _straight(path, u: float) -> bool:
    """Whether the route is a straight line around arc length u (one segment of kind line)."""
    for start, length, kind, _ in path.segments:
        if start <= u % path.length < start + length:
            return kind == "line"
    return False


def place(path, count: int, seed: int, map_name: str) -> List[float]:
    """Arc lengths of up to `count` obstacles on straights of a RoutePath."""
    if count <= 0:
        return []
    candidates = [u for u in np.arange(CLEAR_M, path.length - CLEAR_M, 1.0)
                  if all(_straight(path, u + d) for d in np.arange(-CLEAR_M, CLEAR_M + 0.1, 2.0))]
    rng = np.random.default_rng([seed, zlib.crc32(map_name.encode()), 7])
    chosen: List[float] = []
    for u in rng.permutation(candidates):
        if len(chosen) == count:
            break
        if all(_gap(u, c, path) >= SPACING_M for c in chosen):
            chosen.append(float(u))
    return sorted(chosen)


def _gap(a: float, b: float, path) -> float:
    d = abs(a - b)
    return min(d, path.length - d) if path.closed else d


def _smoothstep(x: float) -> float:
    x = min(max(x, 0.0), 1.0)
    return x * x * (3 - 2 * x)


def _smoothstep_slope(x: float) -> float:
    return 6 * x * (1 - x) if 0 < x < 1 else 0.0


def shift(u: float, obstacles: Sequence[float], path) -> Tuple[float, float]:
    """(metres to the left of the right-lane centre the ideal path is at u, its slope d/du)."""
    best, slope = 0.0, 0.0
    for o in obstacles:
        d = u - o
        if path.closed:
            d = (d + path.length / 2) % path.length - path.length / 2
        a = abs(d)
        if a <= HOLD_M:
            return LANE_SHIFT_M, 0.0
        if a < HOLD_M + RAMP_M:
            x = 1.0 - (a - HOLD_M) / RAMP_M
            s = LANE_SHIFT_M * _smoothstep(x)
            if s > best:
                best = s
                slope = LANE_SHIFT_M * _smoothstep_slope(x) / RAMP_M * (1 if d < 0 else -1)
    return best, slope


class ShiftedPath:
    """A RoutePath whose points move left around obstacles: point(u) like
    RoutePath.point, on the ideal path (exact on the straights the shifts
    are confined to). `lane` is the underlying RoutePath. `offset`: metres
    left of the right lane everywhere (LANE_SHIFT_M: the left lane's centre,
    exact on lines and arcs alike, since the lanes are concentric)."""

    def __init__(self, lane, obstacles: Sequence[float], offset: float = 0.0):
        self.lane = lane
        self.obstacles = list(obstacles)
        self.offset = offset
        self.closed = lane.closed
        self.length = lane.length
        self.segments = lane.segments

    @classmethod
    def placed(cls, lane, count: int, seed: int, map_name: str, offset: float = 0.0) -> "ShiftedPath":
        """The ideal path of `lane` around the `count` obstacles `place` puts
        there (the one placement the dataset, DAgger, relabel and the
        evaluation share)."""
        return cls(lane, place(lane, count, seed, map_name), offset)

    def point(self, u: float) -> Tuple[float, float, float]:
        x, y, heading = self.lane.point(u)
        s, slope = shift(u, self.obstacles, self.lane)
        s += self.offset
        return (x - s * math.sin(heading), y + s * math.cos(heading), heading + math.atan(slope))

    def passing(self, u: float, step: float = 0.0, count: int = 0) -> bool:
        """Whether an obstacle moves the path at u or at any of the `count`
        points `step` apart ahead of it: a pass is under way (with a pose's
        waypoints: its labels leave the daemon's lane; relabel's `obstacle`
        column)."""
        return any(shift(u + step * k, self.obstacles, self.lane)[0] > 0 for k in range(count + 1))

    def deviation(self, u: float, lane_deviation: float) -> float:
        """Signed distance (+ right) from the ideal path, given the signed
        distance from the right-lane centre at arc length u."""
        return lane_deviation + shift(u, self.obstacles, self.lane)[0] + self.offset

    def obstacle_poses(self) -> List[Tuple[float, float, float]]:
        """(x, y, heading rad) of each obstacle: in the right lane, along it."""
        return [self.lane.point(o) for o in self.obstacles]
