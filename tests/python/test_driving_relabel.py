"""sim4cv.driving_relabel: goals at the junctions of a real dataset's route
(test/01_urban turns left at a crossroads where the road also goes on)."""

import csv
import os
import sys

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_eval as de  # noqa: E402
from sim4cv import driving_obstacles as dob  # noqa: E402
from sim4cv import driving_relabel as dr  # noqa: E402

MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")


def test_goals_follow_the_route_at_junctions_and_are_random_elsewhere(tmp_path):
    dd.generate([MAP], ["urban"], str(tmp_path), views="random", random_views=1, straight_step=4.0, turn_step=4.0,
                log=lambda *a: None)
    counts = dr.relabel(str(tmp_path), log=lambda *a: None)
    with open(tmp_path / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert (tmp_path / "labels.csv.bak").is_file()
    nav = de.RouteNavigation(dd.parse_map(MAP), "loop")
    start, end, goal, turn, tile = nav.goals.intervals[0]
    assert (goal, turn, tile) == (-1, "left", (3, 5))  # north along column 3, then west along row 5
    by_sample = {}
    for r in rows:
        by_sample.setdefault(r["sample"], set()).add(r["goal"])
    assert all(len(g) == 1 for g in by_sample.values())  # every view of a pose has the pose's goal
    at_junction = [r for r in rows if start <= int(r["sample"]) * 4.0 <= end]
    assert at_junction and all(r["goal"] == "-1" for r in at_junction)
    elsewhere = {r["goal"] for r in rows if r not in at_junction}
    assert elsewhere == {"-1", "0", "1"}  # random where there is no choice
    assert counts["junction"] >= len(at_junction)
    assert all(r["junction"] == "1" for r in at_junction)  # train --junction-weight reads this
    assert sum(r["junction"] == "1" for r in rows) == counts["junction"]
    assert nav.goal(start + 1.0) == -1.0 and nav.goal(start - 5.0) == 0.0
    assert counts["obstacle"] == 0 and {r["obstacle"] for r in rows} == {"0"}  # generated without obstacles


def test_obstacle_column_marks_the_poses_of_a_pass(tmp_path):
    step = 4.0
    dd.generate([MAP], ["urban"], str(tmp_path), views="random", random_views=1, straight_step=step, turn_step=step,
                obstacles=2, log=lambda *a: None)
    counts = dr.relabel(str(tmp_path), log=lambda *a: None)
    with open(tmp_path / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    lane = dd.RoutePath(dd.parse_map(MAP), "loop")
    placed = dob.place(lane, 2, 0, "driving_test_01_urban")
    assert len(placed) == 2
    # a pose is part of a pass from where its last waypoint (8 m ahead) reaches the
    # first ramp to where the pose leaves the second one
    reach = dob.HOLD_M + dob.RAMP_M
    for r in rows:
        u = int(r["sample"]) * step
        want = any(-reach - 8.0 < u - o < reach for o in placed)
        assert r["obstacle"] == ("1" if want else "0"), (u, placed)
    assert counts["obstacle"] == sum(r["obstacle"] == "1" for r in rows) > 0
