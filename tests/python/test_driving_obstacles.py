"""Obstacles for the driving study (sim4cv.driving_obstacles): placement on
straights, the ideal path passing them in the left lane (hand-computed
shifts), the dataset's labels around them, and the reference policy passing
them in a real closed-loop evaluation without a collision."""

import csv
import math
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_eval as de  # noqa: E402
from sim4cv import driving_obstacles as dob  # noqa: E402

MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")


def lane():
    info = dd.parse_map(MAP)
    return info, dd.RoutePath(info, "loop")


def test_obstacles_sit_on_straights_apart_and_reproducibly():
    info, path = lane()
    placed = dob.place(path, 3, 0, info["name"])
    assert placed == dob.place(path, 3, 0, info["name"])
    assert placed != dob.place(path, 3, 1, info["name"])
    assert 1 <= len(placed) <= 3
    for u in placed:
        assert all(dob._straight(path, u + d) for d in range(-int(dob.CLEAR_M), int(dob.CLEAR_M) + 1))
    for a, b in zip(placed, placed[1:]):
        assert dob._gap(a, b, path) >= dob.SPACING_M
    assert dob.place(path, 0, 0, info["name"]) == []


def test_the_ideal_path_shifts_by_hand_computed_amounts():
    _, path = lane()
    o = 200.0
    assert dob.shift(o, [o], path) == (4.0, 0.0)
    assert dob.shift(o - 10.0, [o], path)[0] == 4.0                 # still held
    assert dob.shift(o + 19.0, [o], path)[0] == pytest.approx(2.0)  # half way back: smoothstep(0.5) = 0.5
    s, slope = dob.shift(o - 19.0, [o], path)
    assert s == pytest.approx(2.0) and slope == pytest.approx(4.0 * 1.5 / 18.0)  # rising towards it
    assert dob.shift(o + 28.0, [o], path) == (0.0, 0.0)
    shifted = dob.ShiftedPath(path, [o])
    x, y, h = shifted.point(o)
    lx, ly, lh = path.point(o)
    assert (x - lx, y - ly) == pytest.approx((-4.0 * math.sin(lh), 4.0 * math.cos(lh)))  # 4 m to the left
    assert shifted.deviation(o, -4.0) == pytest.approx(0.0)  # in the left lane: on the ideal path
    assert shifted.deviation(o, 0.0) == pytest.approx(4.0)   # in its own lane: 4 m right of it


def test_two_car_footprints_overlap_only_where_they_touch():
    assert dob.cars_overlap((0, 0, 0), (4.4, 0, 0))                   # nose to tail, 10 cm into each other
    assert not dob.cars_overlap((0, 0, 0), (4.6, 0, 0))
    assert not dob.cars_overlap((0, 0, 0), (0, 1.9, 0))               # side by side, 10 cm apart
    assert dob.cars_overlap((0, 0, 0), (0, 1.9, 0), margin=0.1)       # ... not with 10 cm more on each side
    assert not dob.cars_overlap((0, 0, 0), (3.2, 0, math.pi / 2))     # across its nose: 2.25 + 0.9 < 3.2
    assert dob.cars_overlap((0, 0, 0), (3.1, 0, math.pi / 2))
    # turned 45 degrees beside it: the corner reaches (0.9 + 2.25) / sqrt(2) = 2.23 m towards it
    assert dob.cars_overlap((0, 0, 0), (0, 0.9 + 2.2, math.pi / 4))
    assert not dob.cars_overlap((0, 0, 0), (0, 0.9 + 2.3, math.pi / 4))
    assert not dob.cars_overlap((0, 0, 0), (0, dob.LANE_SHIFT_M, 0), margin=0.2)  # passing in the left lane


def test_dataset_labels_pass_the_obstacles(tmp_path):
    info, path = lane()
    dd.generate([MAP], ["urban"], str(tmp_path), views="none", straight_step=6.0, turn_step=6.0, obstacles=2,
                log=lambda *a: None)
    placed = dob.place(path, 2, 0, info["name"])
    with open(tmp_path / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    shifted = dob.ShiftedPath(path, placed)
    near = [r for r in rows if any(abs(int(r["sample"]) * 6.0 - o) < 8 for o in placed)]
    assert near, "no sample near an obstacle"
    for r in near:  # on the left lane: the view 4 m left of the right lane's centre, waypoints straight ahead
        u = int(r["sample"]) * 6.0
        lx, ly, lh = path.point(u)
        left = -(float(r["view_x"]) - lx) * math.sin(lh) + (float(r["view_y"]) - ly) * math.cos(lh)
        assert left == pytest.approx(dob.shift(u, placed, path)[0], abs=0.01)
    assert all(abs(float(r["h1"])) < 1.5 for r in rows)
    assert shifted.obstacles == placed


def test_reference_policy_passes_the_obstacles_without_collision(tmp_path):
    report = de.evaluate(de.ReferencePolicy(), [MAP], ["urban"], str(tmp_path), obstacles=2, log=lambda *a: None)
    run = report["maps"]["driving_test_01_urban"]["routes"]["loop"]
    assert run["obstacles"] >= 1 and run["completed"]
    assert run["collisions"] == 0 and run["lane_departures"] == 0
    assert run["mean_deviation_cm"] < 10.0
