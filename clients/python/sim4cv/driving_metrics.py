"""The driving case study's closed-loop score (docs/driving.md, "Closed-loop
evaluation"): how far the car stays from the ideal path, the right-lane
centre line of its route.

The paper (Sim4CV, IJCV 2018, section 5.2) reports the average deviation
from the ideal path and the fraction of time spent within a distance of it
(its cumulative histogram in 5 cm bins). Samples here are taken every
frame, i.e. at a fixed simulated time step, so a fraction of samples is a
fraction of time.

A lane departure is the car crossing its lane's boundary: the lane is 4 m
wide and the car 2 m, so its side leaves the lane when its centre is more
than 1 m from the lane centre; each entry into that state counts once.

Pure functions (numpy), no daemon: tested on hand-computed cases.
"""

import math
from typing import Dict, Iterable, List, Sequence, Tuple

import numpy as np

LANE_DEPARTURE_M = 1.0   # car centre this far from the lane centre: a side is out of the lane
HISTOGRAM_BIN_M = 0.05   # the paper's 5 cm bins
WITHIN_M = (0.25, 0.5, 1.0)


def departures(deviation_m: Sequence[float], limit_m: float = LANE_DEPARTURE_M) -> int:
    """How many times |deviation| went from <= limit to > limit (a run that
    starts beyond the limit counts once)."""
    out = 0
    beyond = False
    for d in deviation_m:
        now = abs(d) > limit_m
        if now and not beyond:
            out += 1
        beyond = now
    return out


def cumulative_histogram(deviation_m: Sequence[float], bin_m: float = HISTOGRAM_BIN_M,
                         max_m: float = 1.0) -> Tuple[List[float], List[float]]:
    """(edges, fractions): fractions[i] is the fraction of samples with
    |deviation| <= edges[i]; edges are bin_m, 2 bin_m, ... up to max_m."""
    d = np.abs(np.asarray(deviation_m, dtype=float))
    count = int(round(max_m / bin_m))
    edges = [round((i + 1) * bin_m, 6) for i in range(count)]
    if d.size == 0:
        return edges, [0.0] * count
    return edges, [float(np.count_nonzero(d <= e + 1e-12)) / d.size for e in edges]


def score(deviation_m: Sequence[float], distance_m: float = 0.0, collisions: int = 0) -> Dict[str, float]:
    """The report's numbers for one run or a pooled set of samples:
    mean_deviation_cm, max_deviation_cm, within_25cm / 50cm / 1m (fractions
    of time), lane_departures, collisions, distance_m, samples."""
    d = np.abs(np.asarray(deviation_m, dtype=float))
    out = {"samples": int(d.size), "distance_m": round(float(distance_m), 2), "collisions": int(collisions),
           "lane_departures": departures(d)}
    if d.size == 0:
        out.update(mean_deviation_cm=None, max_deviation_cm=None,
                   **{_within_key(w): None for w in WITHIN_M})
        return out
    out["mean_deviation_cm"] = round(float(d.mean()) * 100.0, 3)
    out["max_deviation_cm"] = round(float(d.max()) * 100.0, 3)
    for w in WITHIN_M:
        out[_within_key(w)] = round(float(np.count_nonzero(d <= w)) / d.size, 5)
    return out


def _within_key(w: float) -> str:
    return "within_1m" if w == 1.0 else "within_%dcm" % round(w * 100)


def pooled(runs: Iterable[dict], deviations: Iterable[Sequence[float]]) -> Dict[str, float]:
    """One score over several runs: samples pooled (so longer runs weigh
    more, as time does), departures, collisions and distances summed."""
    runs = list(runs)
    deviations = [np.asarray(d, dtype=float) for d in deviations]
    joined = np.concatenate(deviations) if deviations else np.zeros(0)
    out = score(joined, sum(r["distance_m"] for r in runs), sum(r["collisions"] for r in runs))
    out["lane_departures"] = sum(r["lane_departures"] for r in runs)  # runs are separate: no joined crossings
    out["runs"] = len(runs)
    out["completed"] = sum(1 for r in runs if r.get("completed"))
    return out


# The paper's Table (Sim4CV, IJCV 2018, "Investigating the Impact of
# Augmentation": its best random-view and fixed-view networks on the test maps).
PAPER = {
    "random": {"within_25cm": 0.9550, "within_50cm": 0.9966, "within_1m": 1.0000, "mean_deviation_cm": 7.1205},
    "fixed": {"within_25cm": 0.8944, "within_50cm": 0.9680, "within_1m": 0.9954, "mean_deviation_cm": 14.6129},
}


def signed_distance_to_segment(px: float, py: float, segment) -> Tuple[float, float]:
    """(s, d) for a RoutePath segment (start_u, length, kind, params): s is
    the arc length along the segment of the nearest point (clamped to the
    segment), d the signed distance from it to (px, py), POSITIVE TO THE
    RIGHT of the direction of travel."""
    _, length, kind, p = segment
    if kind == "line":
        (ex, ey), heading = p
        c, s_ = math.cos(heading), math.sin(heading)
        s = min(max((px - ex) * c + (py - ey) * s_, 0.0), length)
        qx, qy = ex + s * c, ey + s * s_
        # right of travel = (sin, -cos)
        side = (px - qx) * s_ - (py - qy) * c
        dist = math.hypot(px - qx, py - qy)
        return s, math.copysign(dist, side) if dist > 0 else 0.0
    cx, cy, r, a0, ccw = p
    a = math.atan2(py - cy, px - cx)
    delta = math.atan2(math.sin(a - a0), math.cos(a - a0)) * ccw  # angle travelled from the entry
    s = min(max(delta * r, 0.0), length)
    ang = a0 + ccw * s / r
    qx, qy = cx + r * math.cos(ang), cy + r * math.sin(ang)
    dist = math.hypot(px - qx, py - qy)
    radial = math.hypot(px - cx, py - cy) - r  # > 0: outside the circle
    # turning left (ccw) the outside is on the right; turning right it is on the left
    side = radial if ccw > 0 else -radial
    return s, math.copysign(dist, side) if dist > 0 else 0.0


def nearest_u(path, x: float, y: float) -> float:
    """Arc length of the lane point nearest to (x, y) over the whole route
    (Progress then follows it locally)."""
    best = min(((signed_distance_to_segment(x, y, seg), seg[0]) for seg in path.segments),
               key=lambda item: abs(item[0][1]))
    return best[1] + best[0][0]


class Progress:
    """Follows a car along a RoutePath: its arc length u (unwrapped: keeps
    growing past a closed route's length) and its signed deviation from the
    lane centre. Searches the segments near the last one, so a route that
    crosses itself at a junction never jumps to the other pass."""

    def __init__(self, path, u0: float = 0.0, window: int = 2):
        self.path = path
        self.window = window
        n = len(path.segments)
        self.index = self._segment_at(u0 % path.length if path.closed else u0)
        self.lap = math.floor(u0 / path.length) if path.closed else 0
        self.u = u0
        self.n = n

    def _segment_at(self, u: float) -> int:
        for i, seg in enumerate(self.path.segments):
            if seg[0] <= u < seg[0] + seg[1]:
                return i
        return len(self.path.segments) - 1

    def update(self, x: float, y: float) -> float:
        """Moves to the nearest lane point to (x, y); returns the signed deviation (m, + right)."""
        best = None
        for k in range(-self.window, self.window + 1):
            i = self.index + k
            if self.path.closed:
                i %= self.n
            elif not 0 <= i < self.n:
                continue
            s, d = signed_distance_to_segment(x, y, self.path.segments[i])
            if best is None or abs(d) < abs(best[2]) - 1e-9:
                best = (i, s, d)
        i, s, d = best
        if self.path.closed:
            if i < self.index and self.index - i > self.n // 2:
                self.lap += 1
            elif i > self.index and i - self.index > self.n // 2:
                self.lap -= 1
        self.index = i
        self.u = self.lap * self.path.length + self.path.segments[i][0] + s
        return d


# ---------------------------------------------------------------------------
# Collisions with the map's objects, geometrically (the daemon reports no
# contacts): the car's footprint (CarParams' chassis, 4.5 x 1.8 m) against
# each object's footprint (server/sim/map/map.cpp ShapeOf: houses and
# obstacles as rectangles, cars parked as obstacles as their chassis, tree trunks and lanterns as discs; parks are flat
# and never hit). Each entry into contact with an object counts once.

CAR_HALF_LENGTH_M, CAR_HALF_WIDTH_M = 2.25, 0.9
OBJECT_SHAPES = {"house": ("box", 5.0, 4.0), "obstacle": ("box", 1.0, 0.5), "car": ("box", 2.25, 0.9),
                 "tree": ("disc", 0.3), "lantern": ("disc", 0.15)}


def _box_corners(x, y, yaw, hx, hy):
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * a - s * b, y + s * a + c * b) for a, b in ((hx, hy), (hx, -hy), (-hx, -hy), (-hx, hy))]


def _box_disc_distance(x, y, yaw, hx, hy, px, py):
    c, s = math.cos(yaw), math.sin(yaw)
    a, b = (px - x) * c + (py - y) * s, -(px - x) * s + (py - y) * c
    return math.hypot(max(abs(a) - hx, 0.0), max(abs(b) - hy, 0.0))


def _boxes_overlap(b1, b2) -> bool:
    """Separating-axis test of two oriented rectangles (x, y, yaw, hx, hy)."""
    corners = (_box_corners(*b1), _box_corners(*b2))
    for yaw in (b1[2], b1[2] + math.pi / 2, b2[2], b2[2] + math.pi / 2):
        ax, ay = math.cos(yaw), math.sin(yaw)
        p1 = [px * ax + py * ay for px, py in corners[0]]
        p2 = [px * ax + py * ay for px, py in corners[1]]
        if max(p1) < min(p2) or max(p2) < min(p1):
            return False
    return True


class Collisions:
    """Counts the car's contacts with a map's objects [(kind, x, y, yaw_deg)]."""

    def __init__(self, objects: Sequence[Tuple[str, float, float, float]]):
        self.objects = [(k, x, y, math.radians(yaw)) for k, x, y, yaw in objects if k in OBJECT_SHAPES]
        self.touching = set()
        self.count = 0

    def touches(self, car_x: float, car_y: float, car_yaw: float, index: int) -> bool:
        kind, x, y, yaw = self.objects[index]
        shape = OBJECT_SHAPES[kind]
        if shape[0] == "disc":
            return _box_disc_distance(car_x, car_y, car_yaw, CAR_HALF_LENGTH_M, CAR_HALF_WIDTH_M, x, y) <= shape[1]
        return _boxes_overlap((car_x, car_y, car_yaw, CAR_HALF_LENGTH_M, CAR_HALF_WIDTH_M),
                              (x, y, yaw, shape[1], shape[2]))

    def update(self, car_x: float, car_y: float, car_yaw: float) -> int:
        """Checks the objects within 8 m; returns how many new contacts began."""
        now = set()
        for i, (_, x, y, _) in enumerate(self.objects):
            if abs(x - car_x) < 8.0 and abs(y - car_y) < 8.0 and self.touches(car_x, car_y, car_yaw, i):
                now.add(i)
        new = len(now - self.touching)
        self.touching = now
        self.count += new
        return new
