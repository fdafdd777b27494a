"""Labels of the driving case study (docs/driving.md, "Dataset"): waypoints
ahead of a car encoded relative to a camera view, and the view augmentation.

Pure Python (numpy only for the random generator); no daemon.

World frame: x east, y north, headings radians counter-clockwise from east
(docs/maps.md). A view is (x, y, yaw). For a world point P:

    v = distance along the viewing axis (forward) from the view to P
    h = signed distance from P to the viewing axis, POSITIVE TO THE RIGHT

              h < 0 (left)
        view ----------------> forward (v)
              h > 0 (right)

so atan2(h1, v1) > 0 means "steer right", as sim4cv's Controls.steering
(+1 = full right).
"""

import math
from typing import Iterable, List, Sequence, Tuple

# "fixed" augmentation: every combination of these (the (0, 0) one is the
# original view). Sideways offset in metres, positive to the right; yaw
# offset in degrees, positive counter-clockwise (to the left), as world yaw.
FIXED_OFFSETS_M = (-2.0, -1.0, 0.0, 1.0, 2.0)
FIXED_YAWS_DEG = (-20.0, -10.0, 0.0, 10.0, 20.0)
# "random" augmentation: uniform in [-RANDOM_OFFSET_M, RANDOM_OFFSET_M] and
# [-RANDOM_YAW_DEG, RANDOM_YAW_DEG].
RANDOM_OFFSET_M = 4.0
RANDOM_YAW_DEG = 30.0
DEFAULT_RANDOM_VIEWS = 4
VIEW_MODES = ("random", "fixed", "none")


def encode(view_x: float, view_y: float, view_yaw_rad: float,
           waypoints: Iterable[Sequence[float]]) -> List[Tuple[float, float]]:
    """[(v, h), ...] of world waypoints [(x, y), ...] seen from the view:
    v forward along the viewing axis, h to the right of it."""
    c, s = math.cos(view_yaw_rad), math.sin(view_yaw_rad)
    out = []
    for px, py in waypoints:
        dx, dy = px - view_x, py - view_y
        out.append((dx * c + dy * s, dx * s - dy * c))
    return out


def decode(view_x: float, view_y: float, view_yaw_rad: float,
           labels: Iterable[Sequence[float]]) -> List[Tuple[float, float]]:
    """The inverse of encode: world (x, y) of each (v, h)."""
    c, s = math.cos(view_yaw_rad), math.sin(view_yaw_rad)
    return [(view_x + v * c + h * s, view_y + v * s - h * c) for v, h in labels]


def steering_angle(v: float, h: float) -> float:
    """atan(h / v) in radians: positive = the point is to the right."""
    return math.atan2(h, v)


def offset_pose(x: float, y: float, yaw: float, sideways_m: float, yaw_deg: float) -> Tuple[float, float, float]:
    """The view `sideways_m` metres to the right of (x, y, yaw) (along the
    normal of the heading), turned `yaw_deg` degrees counter-clockwise."""
    return (x + sideways_m * math.sin(yaw), y - sideways_m * math.cos(yaw), yaw + math.radians(yaw_deg))


def augment_poses(x: float, y: float, yaw: float, mode: str, rng=None, n: int = DEFAULT_RANDOM_VIEWS,
                  max_offset_m: float = RANDOM_OFFSET_M, max_yaw_deg: float = RANDOM_YAW_DEG,
                  offsets_m: Sequence[float] = FIXED_OFFSETS_M, yaws_deg: Sequence[float] = FIXED_YAWS_DEG):
    """The augmented views of the lane pose (x, y, yaw), WITHOUT the original:
    a list of (view_x, view_y, view_yaw, sideways_m, yaw_offset_deg).

    "random": n views, sideways offset uniform in [-max_offset_m, max_offset_m]
    (positive right), yaw offset uniform in [-max_yaw_deg, max_yaw_deg]
    (positive left); `rng` a numpy Generator (or anything with .uniform).
    "fixed": every (offset, yaw) of offsets_m x yaws_deg except (0, 0).
    "none": no views."""
    if mode == "none":
        return []
    if mode == "random":
        if rng is None:
            raise ValueError("augment_poses: mode 'random' needs rng")
        combos = [(float(rng.uniform(-max_offset_m, max_offset_m)), float(rng.uniform(-max_yaw_deg, max_yaw_deg)))
                  for _ in range(n)]
    elif mode == "fixed":
        combos = [(float(o), float(a)) for o in offsets_m for a in yaws_deg if not (o == 0 and a == 0)]
    else:
        raise ValueError("augment_poses: mode %r is not one of %s" % (mode, ", ".join(VIEW_MODES)))
    return [offset_pose(x, y, yaw, o, a) + (o, a) for o, a in combos]


def all_views(x: float, y: float, yaw: float, mode: str, rng=None, n: int = DEFAULT_RANDOM_VIEWS,
              max_offset_m: float = RANDOM_OFFSET_M, max_yaw_deg: float = RANDOM_YAW_DEG):
    """The original view (offsets 0, 0) followed by augment_poses()."""
    return [(x, y, yaw, 0.0, 0.0)] + augment_poses(x, y, yaw, mode, rng, n, max_offset_m, max_yaw_deg)
