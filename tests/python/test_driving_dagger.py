"""sim4cv.driving_dagger and drive_route's takeover on the real daemon: a
policy that pulls left is caught by the reference policy each time it gets
1 m off the ideal path, and the poses it drove into are rendered and
labelled with the lane's waypoints re-encoded for them."""

import csv
import json
import math
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_dagger as dg  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_eval as de  # noqa: E402
from sim4cv import driving_labels as dl  # noqa: E402
from sim4cv import driving_metrics as dm  # noqa: E402
from sim4cv import driving_obstacles as dob  # noqa: E402

TEST_MAP = os.path.join(REPO_ROOT, "scenes", "driving", "val", "04_desert.map")


class PullsLeft(de.ReferencePolicy):
    """The true waypoints moved 1.5 m to the left: the car drifts off the lane."""
    name = "pulls_left"

    def waypoints(self, rgb, pose, progress):
        w = super().waypoints(rgb, pose, progress)
        return [v - 1.5 if i % 2 else v for i, v in enumerate(w)]


class IgnoresObstacles(de.ReferencePolicy):
    """The right lane's true waypoints, as if no car were parked in it."""
    name = "ignores_obstacles"

    def waypoints(self, rgb, pose, progress):
        x, y, yaw = pose
        lane = progress.path.lane
        points = [lane.point(progress.u + 2.0 * k)[:2] for k in range(1, 5)]
        return [c for vh in dl.encode(x, y, yaw, points) for c in vh]


def test_pick_poses_keeps_the_poses_off_the_lane_once_per_step():
    info = dd.parse_map(TEST_MAP)
    lane = dd.RoutePath(info, "loop")
    rows = []
    for k in range(40):  # every 0.25 m: on the lane for 5 m, then 0.5 m to the right turned 3 degrees left
        u = 0.25 * k
        x, y, yaw = lane.point(u)
        side, turn = (0.0, 0.0) if u < 5 else (0.5, 3.0)
        vx, vy, vyaw = dl.offset_pose(x, y, yaw, side, turn)
        rows.append(dict(u=u, x=vx, y=vy, yaw_deg=math.degrees(vyaw)))
    rows.append(dict(u=20.0, x=lane.point(20.0)[0] + 10.0, y=lane.point(20.0)[1], yaw_deg=0.0))  # 10 m off: beyond
    picked = dg.pick_poses(rows, lane, every_m=1.0)
    assert [u for u, _ in picked] == [5.0, 6.0, 7.0, 8.0, 9.0]
    for u, (lane_view, driven) in picked:
        assert lane_view[3:] == (0.0, 0.0) and lane_view[:3] == pytest.approx(lane.point(u))
        assert driven[3] == pytest.approx(0.5, abs=1e-6) and driven[4] == pytest.approx(3.0, abs=1e-6)


def test_a_policy_that_pulls_left_is_caught_and_its_states_become_a_dataset(tmp_path):
    meta = dg.collect(PullsLeft(), [TEST_MAP], ["desert"], str(tmp_path), takeover_m=1.0, every_m=2.0,
                      min_offset_m=0.1, min_yaw_deg=2.0, log=lambda *a: None)
    with open(tmp_path / "drives" / "driving.json") as f:
        run = json.load(f)["maps"]["driving_val_04_desert"]["routes"]["loop"]
    assert run["completed"] and run["takeovers"] >= 3 and run["expert_frames"] > 0
    assert run["lane_departures"] >= run["takeovers"] - 1 and run["max_deviation_cm"] < 200
    assert meta["settings"]["dagger"]["model"] == "pulls_left" and meta["counts"]["images"] >= 40

    with open(tmp_path / "labels.csv") as f:
        rows = list(csv.DictReader(f))
    assert {"goal", "junction"} <= set(rows[0]) and len(rows) == meta["counts"]["images"]
    driven = [r for r in rows if float(r["offset_side_m"]) or float(r["offset_yaw_deg"])]
    assert len(driven) == len(rows) // 2
    assert all(float(r["offset_side_m"]) < 0 for r in driven[:5])  # pulled left: negative is left
    by_sample = {(r["sample"], float(r["offset_side_m"]) == 0): r for r in rows}
    for r in driven:  # the driven view's labels are the lane view's waypoints, re-encoded
        lane_row = by_sample[(r["sample"], True)]
        points = [dl.decode(float(q["view_x"]), float(q["view_y"]), math.radians(float(q["view_yaw_deg"])),
                            [(float(q["v%d" % i]), float(q["h%d" % i])) for i in range(1, 5)])
                  for q in (r, lane_row)]
        for a, b in zip(*points):
            assert a == pytest.approx(b, abs=0.01)

    # the same folder with other settings is refused before any driving
    with pytest.raises(dd.DatasetError, match="other settings"):
        dg.collect(PullsLeft(), [TEST_MAP], ["desert"], str(tmp_path), takeover_m=2.0, every_m=2.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, log=lambda *a: None)
    with pytest.raises(dd.DatasetError, match="--takeover 0.1: more than 0.2 m"):
        dg.collect(PullsLeft(), [TEST_MAP], ["desert"], str(tmp_path / "x"), takeover_m=0.1, every_m=2.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, log=lambda *a: None)


def test_bad_settings_and_an_unreadable_dataset_are_refused_before_driving(tmp_path):
    with pytest.raises(dd.DatasetError, match="--every must be positive, got 0"):
        dg.collect(PullsLeft(), [TEST_MAP], ["desert"], str(tmp_path / "a"), takeover_m=1.0, every_m=0.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, log=lambda *a: None)
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "dataset.json").write_text("{not json")
    with pytest.raises(dd.DatasetError, match=r"dataset.json is unreadable .*refusing to overwrite it"):
        dg.collect(PullsLeft(), [TEST_MAP], ["desert"], str(tmp_path / "b"), takeover_m=1.0, every_m=2.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, log=lambda *a: None)
    assert (tmp_path / "b" / "dataset.json").read_text() == "{not json"
    assert not (tmp_path / "b" / "drives" / "driving.json").exists()


def test_with_obstacles_the_pass_a_policy_misses_is_taken_over_and_labelled(tmp_path):
    meta = dg.collect(IgnoresObstacles(), [TEST_MAP], ["desert"], str(tmp_path), takeover_m=1.0, every_m=1.0,
                      min_offset_m=0.1, min_yaw_deg=2.0, obstacles=1, log=lambda *a: None)
    with open(tmp_path / "drives" / "driving.json") as f:
        run = json.load(f)["maps"]["driving_val_04_desert"]["routes"]["loop"]
    # the policy stays in the right lane: the reference takes over as the ideal path leaves it, and
    # drives until the pass is over (a hand-back beside the parked car would steer into it)
    assert run["obstacles"] == 1 and run["takeovers"] == 1 and run["collisions"] == 0 and run["completed"]
    assert meta["settings"]["dagger"]["obstacles"] == 1 and meta["settings"]["obstacles"] == 1
    with open(tmp_path / "labels.csv") as f:
        rows = list(csv.DictReader(f))
    lane = dd.RoutePath(dd.parse_map(TEST_MAP), "loop")
    ideal = dob.ShiftedPath(lane, dob.place(lane, 1, 0, "driving_val_04_desert"))
    passing = [r for r in rows if r["obstacle"] == "1" and float(r["offset_side_m"]) == 0
               and float(r["offset_yaw_deg"]) == 0]
    assert passing
    shifted = 0
    for r in passing:  # the lane view is the ideal path's pose, in the left lane beside the car
        x, y = float(r["view_x"]), float(r["view_y"])
        u = dm.nearest_u(lane, x, y)
        assert (x, y) == pytest.approx(ideal.point(u)[:2], abs=0.05)
        shifted += math.dist((x, y), lane.point(u)[:2]) > 1.0
    assert shifted > 0
    # the other obstacle count is other settings
    with pytest.raises(dd.DatasetError, match="other settings"):
        dg.collect(IgnoresObstacles(), [TEST_MAP], ["desert"], str(tmp_path), takeover_m=1.0, every_m=1.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, obstacles=2, log=lambda *a: None)
    with pytest.raises(dd.DatasetError, match="--obstacles must be 0 or more, got -1"):
        dg.collect(IgnoresObstacles(), [TEST_MAP], ["desert"], str(tmp_path / "n"), takeover_m=1.0, every_m=1.0,
                   min_offset_m=0.1, min_yaw_deg=2.0, obstacles=-1, log=lambda *a: None)
