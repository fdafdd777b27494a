"""Guided driving (sim4cv.driving_guided, docs/driving_guided.md): the goal
labels of routes through a known crossroads (hand-checked), the seeded
random goals away from junctions, the exit a car takes read from
hand-made trajectories, the navigator's commands, the shipped maps' routes
covering every junction choice, and with a real sim4cvd a tiny dataset's
goal column and the reference policy taking every commanded exit."""

import csv
import json
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_guided as dg  # noqa: E402

GUIDED = os.path.join(REPO_ROOT, "scenes", "driving", "guided")

# A 3 x 3 lattice of 20 m tiles: a crossroads at tile 2,2 (world origin),
# T-junctions in the middle of each side, bends in the corners.
#   tile (c, r) has its centre at x = (c - 2) * 20, y = (2 - r) * 20
LATTICE = """sim4cv-map 1
name lattice
tile_size 20
grid 5 5
#####
#.#.#
#####
#.#.#
#####
end
route loop closed
tiles 0,0 0,1 0,2 0,3 0,4 1,4 2,4 3,4 4,4 4,3 4,2 4,1 4,0 3,0 2,0 1,0
route left open
tiles 2,4 2,3 2,2 1,2 0,2
route straight open
tiles 2,4 2,3 2,2 2,1 2,0
route right open
tiles 2,4 2,3 2,2 3,2 4,2
"""


@pytest.fixture
def lattice(tmp_path):
    path = tmp_path / "lattice.map"
    path.write_text(LATTICE)
    return str(path)


def test_the_grid_and_turns_by_hand(lattice):
    grid = dg.RoadGrid.from_map(lattice)
    assert grid.conn[(2, 2)] == frozenset("NESW")            # crossroads
    assert grid.conn[(2, 4)] == frozenset("NEW")             # T-junction on the south edge
    assert grid.conn[(0, 0)] == frozenset("ES")              # bend
    assert grid.junctions() == [(2, 0), (0, 2), (2, 2), (4, 2), (2, 4)]
    assert grid.tile_at(0.0, 0.0) == (2, 2) and grid.tile_at(-12.0, 2.0) == (1, 2)
    assert grid.centre((1, 2)) == (-20.0, 0.0)
    # entering through the south side means driving north: west is left, east right
    assert dg.turn_of("S", "W") == "left" and dg.turn_of("S", "N") == "straight" and dg.turn_of("S", "E") == "right"
    assert dg.turn_of("E", "S") == "left" and dg.turn_of("E", "N") == "right" and dg.turn_of("E", "E") == "uturn"
    assert grid.exits((2, 4), "W") == {"straight": "E", "left": "N"}
    # explicit connection codes: two streets side by side that do not join
    side_by_side = dg.RoadGrid.from_rows(["2aa8", "2aa8"])
    assert side_by_side.conn[(1, 0)] == frozenset("EW") and not side_by_side.junctions()


def test_goal_labels_of_routes_through_a_known_crossroads(lattice):
    info = dd.parse_map(lattice)
    grid = dg.RoadGrid.from_map(lattice)
    expected = {"left": (-1, 1.0), "straight": (0, None), "right": (1, -1.0)}
    for route, (goal, ccw) in expected.items():
        junctions = dg.route_junctions(grid, info["routes"][route][1], closed=False)
        assert [(j["tile"], j["entry"], j["turn"], j["goal"]) for j in junctions] == [((2, 2), "S", route, goal)]
        goals = dg.RouteGoals(info, grid, route, seed=0)
        path = goals.path
        # segment 0 is tile 2,3 (a straight, u 0..20); segment 1 the crossroads
        start, length, kind, params = path.segments[1]
        assert start == pytest.approx(20.0)
        if ccw is None:
            assert kind == "line" and length == pytest.approx(20.0)
        else:  # the lane really turns that way: a left turn is counter-clockwise, radius 12 m; right 8 m
            assert kind == "arc" and params[4] == ccw
            assert params[2] == pytest.approx(12.0 if ccw > 0 else 8.0)
        for u in (0.0, 5.0, 19.9, 20.0, 20.0 + length / 2, 20.0 + length):  # from 20 m before it until through it
            assert goals.goal(u) == goal, (route, u)
        after = [goals.goal(20.0 + length + 0.5 + 0.25 * k) for k in range(40)]
        assert after == [dg.random_goal(0, "lattice", route, 20.0 + length + 0.5 + 0.25 * k) for k in range(40)]
        assert set(after) == {-1, 0, 1}  # random there, not the junction's goal
    # the closed loop passes the four T-junctions of the edges, always straight on
    loop = dg.route_junctions(grid, info["routes"]["loop"][1], closed=True)
    assert [(j["tile"], j["turn"]) for j in loop] == [((0, 2), "straight"), ((2, 4), "straight"),
                                                     ((4, 2), "straight"), ((2, 0), "straight")]
    # a closed route's u wraps: tile 2,0 is the loop's 15th tile (segment 14)
    goals = dg.RouteGoals(info, grid, "loop", seed=0)
    u_junction_2_0 = goals.path.segments[14][0] + 1.0
    assert goals.junction_at(u_junction_2_0)[2] == (2, 0)
    assert goals.junction_at(u_junction_2_0 + goals.path.length)[2] == (2, 0)


def test_random_goals_away_from_junctions_are_seeded(lattice):
    us = [0.37 * k for k in range(300)]
    a = [dg.random_goal(7, "m", "r", u) for u in us]
    assert a == [dg.random_goal(7, "m", "r", u) for u in us]
    b = [dg.random_goal(8, "m", "r", u) for u in us]
    assert a != b
    for g in (-1, 0, 1):  # about a third each
        assert 70 <= a.count(g) <= 130
    # the dataset's goal function gives the same goals on a new object, other ones with another seed
    g1 = dg.MapGoals(lattice, seed=3)
    g2 = dg.MapGoals(lattice, seed=3)
    g3 = dg.MapGoals(lattice, seed=4)
    loop = [g1("loop", u) for u in us]
    assert loop == [g2("loop", u) for u in us]
    assert loop != [g3("loop", u) for u in us]
    assert g1.counts["junction"] > 0 and g1.counts["random"] > 0


def test_exit_detection_on_hand_made_trajectories(lattice):
    grid = dg.RoadGrid.from_map(lattice)
    north_in = [(2.0, -35.0), (2.0, -25.0), (2.0, -12.0), (2.0, -8.0)]  # northbound lane into the crossroads
    left = north_in + [(1.0, -2.0), (-4.0, 1.0), (-12.0, 2.0), (-25.0, 2.0)]
    straight = north_in + [(2.0, 0.0), (2.0, 9.0), (2.0, 12.0), (2.0, 25.0)]
    right = north_in + [(5.0, -5.0), (9.0, -2.0), (12.0, -2.0), (25.0, -2.0)]
    for points, turn, exit_ in ((left, "left", "W"), (straight, "straight", "N"), (right, "right", "E")):
        passages = dg.junction_passages(grid, points)
        assert passages == [{"tile": (2, 2), "entry": "S", "exit": exit_, "turn": turn}]
    # the trajectory ends inside the junction: no exit
    assert dg.junction_passages(grid, north_in + [(2.0, 0.0)]) == [
        {"tile": (2, 2), "entry": "S", "exit": None, "turn": None}]
    # off the road across the empty tile 1,1 to the road tile 0,1: no exit, lost
    tracker = dg.TileTracker(grid, grid.tile_at(*north_in[0]))
    for p in north_in + [(-5.0, 5.0), (-15.0, 15.0), (-45.0, 15.0)]:  # 2,2 -> 1,1 (empty) -> 0,1
        tracker.update(*p)
    assert tracker.lost and tracker.finish()[0]["exit"] is None
    # wandering off the road and back onto the same tile changes nothing
    assert dg.junction_passages(grid, [(2.0, -25.0), (-15.0, -25.0), (2.0, -25.0)]) == []
    # two junctions in a row: straight through the crossroads, then left at the T on the north edge
    two = straight + [(2.0, 32.0), (2.0, 38.0), (-2.0, 42.0), (-12.0, 42.0), (-25.0, 42.0)]
    assert [(p["tile"], p["turn"]) for p in dg.junction_passages(grid, two)] == [((2, 2), "straight"),
                                                                                  ((2, 0), "left")]


class FixedRng:
    """Always draws option `index` (options sorted left, straight, right)."""

    def __init__(self, index):
        self.index = index

    def integers(self, n):
        return min(self.index, n - 1)


def test_navigator_commands_and_replanning(lattice):
    grid = dg.RoadGrid.from_map(lattice)
    nav = dg.Navigator(grid, FixedRng(0), (2, 4), (2, 3))  # northbound on 2,3; always commands "left"
    assert nav.goal() == -1
    assert nav.planned_tiles()[:4] == [(2, 4), (2, 3), (2, 2), (1, 2)]
    # the car goes straight on instead: a passage not as commanded, and a new plan from 2,1
    for p in [(2.0, -12.0), (2.0, -8.0), (2.0, 0.0), (2.0, 12.0)]:
        nav.update(*p)
    assert [(r["tile"], r["commanded"], r["turn"], r["ok"]) for r in nav.records] == [
        ((2, 2), "left", "straight", False)]
    assert nav.planned_tiles()[:3] == [(2, 2), (2, 1), (2, 0)]
    assert nav.goal() == -1  # the T-junction ahead (2,0): left is west
    for p in [(2.0, 30.0), (2.0, 38.0), (-2.0, 42.0), (-12.0, 42.0)]:
        nav.update(*p)
    assert [(r["tile"], r["ok"]) for r in nav.records] == [((2, 2), False), ((2, 0), True)]
    # "right" where there is no right (the T entered from the east offers straight and left): the draw
    # is among the junction's exits only
    nav = dg.Navigator(grid, FixedRng(2), (4, 0), (3, 0))  # westbound on the north edge towards 2,0
    assert nav.plan[2] == ((2, 0), "straight")


def test_the_shipped_maps_routes_take_every_junction_choice():
    import glob
    maps = sorted(glob.glob(os.path.join(GUIDED, "*", "*.map")))
    assert len(maps) >= 10  # 5 or more layouts, desert and urban
    kinds = {"t": 0, "x": 0}
    for path in maps:
        info = dd.parse_map(path)
        grid = dg.RoadGrid.from_map(path)
        kinds["t"] += sum(1 for j in grid.junctions() if len(grid.conn[j]) == 3)
        kinds["x"] += sum(1 for j in grid.junctions() if len(grid.conn[j]) == 4)
        assert grid.width >= 16 and grid.height >= 16 and len(grid.junctions()) >= 8, path
        taken = set()
        for name, (closed, tiles) in info["routes"].items():
            n = len(tiles)
            for i in range(n if closed else n - 1):  # consecutive tiles are joined by road
                a, b = tiles[i], tiles[(i + 1) % n]
                side = dg.side_towards(a, b)
                assert side in grid.conn[a], (path, name, a, b)
            for j in dg.route_junctions(grid, tiles, closed):
                assert j["turn"] in dg.GOAL, (path, name, j)
                taken.add((j["tile"], j["entry"], j["exit"]))
            dd.RoutePath(info, name)  # no U-turns
        assert taken == set(dg.junction_choices(grid)), path
    assert kinds["t"] > 0 and kinds["x"] > 0


def test_a_tiny_dataset_carries_the_goals(tmp_path):
    path = os.path.join(GUIDED, "test", "01_desert.map")
    out = str(tmp_path / "ds")
    meta = dg.generate([path], ["desert"], out, views="random", random_views=1, straight_step=4.0,
                       turn_step=4.0, max_samples=12, seed=5, log=lambda *_: None)
    counts = meta["maps"]["guided_test_01_desert"]
    assert counts["samples"] == 12 and counts["images"] == 24
    goals = dg.MapGoals(path, seed=5)
    info = dd.parse_map(path)
    with open(os.path.join(out, "labels.csv")) as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == dd.COLUMNS
    first_route = next(iter(info["routes"]))
    lane = dd.RoutePath(info, first_route)
    us = list(dd.lane_samples(lane, 4.0, 4.0))[:12]
    for row in rows:
        assert row["route"] == first_route
        assert int(row["goal"]) == goals(first_route, us[int(row["sample"])])
    assert counts["goals"]["junction"] + counts["goals"]["random"] == 12
    # the lane poses re-enumerated from dataset.json (goal_probe): junction rows carry their turn's goal
    probed = dg.dataset_junction_rows(out)
    assert [r["image"] for r in probed] == [r["image"] for r in rows]
    for r in probed:
        assert r["u"] == pytest.approx(us[int(r["sample"])])
        if r["junction"] is not None:
            assert int(r["goal"]) == dg.GOAL[r["junction"]]
    # the same settings resume; other settings are refused
    dg.generate([path], ["desert"], out, views="random", random_views=1, straight_step=4.0, turn_step=4.0,
                max_samples=12, seed=5, log=lambda *_: None)
    with pytest.raises(dd.DatasetError, match="other settings"):
        dg.generate([path], ["desert"], out, views="random", random_views=1, straight_step=4.0, turn_step=4.0,
                    max_samples=12, seed=5, before_m=10.0, log=lambda *_: None)


def test_guided_images_may_be_randomised_with_a_car_under_each_view(tmp_path):
    path = os.path.join(GUIDED, "test", "01_desert.map")
    made = {}
    for name, extra in (("plain", {}), ("randomised", dict(randomize=3, ego_car=True))):
        meta = dg.generate([path], ["desert"], str(tmp_path / name), views="none", straight_step=4.0,
                           turn_step=4.0, max_samples=4, seed=5, log=lambda *_: None, **extra)
        made[name] = meta
    assert made["randomised"]["settings"]["randomize"] == 3 and made["randomised"]["settings"]["ego_car"] is True
    assert "ego_car" not in made["plain"]["settings"]
    import cv2
    for i in range(4):  # the same views, labels and goals; other light
        images = [cv2.imread(str(tmp_path / name / "images" / "guided_test_01_desert" / ("%06d.png" % i)))
                  for name in ("plain", "randomised")]
        assert float(abs(images[0].astype(float) - images[1].astype(float)).mean()) > 5
    with open(tmp_path / "plain" / "labels.csv") as a, open(tmp_path / "randomised" / "labels.csv") as b:
        assert list(csv.DictReader(a)) == list(csv.DictReader(b))


def test_the_reference_policy_takes_every_commanded_exit(tmp_path):
    out = str(tmp_path / "eval")
    rc = dg.main(["evaluate", "--policy", "reference", "--maps", os.path.join(GUIDED, "test", "01_desert.map"),
                  "--runs", "1", "--junctions", "5", "--seed", "0", "--out", out])
    assert rc == 0
    with open(os.path.join(out, "guided.json")) as f:
        report = json.load(f)
    o = report["overall"]
    assert o["junctions"] == 5 and o["fraction_as_commanded"] == 1.0
    assert o["left_road"] == 0 and o["lane_departures"] == 0
    assert o["mean_deviation_cm"] < 10.0
    run = report["maps"]["guided_test_01_desert"]["runs"][0]
    assert run["reason"] == "junctions" and run["deviation_from"] == "driven_tiles"
    assert all(p["taken"] == p["commanded"] for p in run["passages"])
    assert len({p["commanded"] for p in run["passages"]}) >= 2
    with open(os.path.join(out, "runs", "guided_test_01_desert_0.csv")) as f:
        rows = list(csv.DictReader(f))
    assert rows and set(rows[0]) == set(dg.ROW_COLUMNS)
    assert {int(r["goal"]) for r in rows} <= {-1, 0, 1}


def test_evaluate_refuses_a_missing_model(tmp_path, capsys):
    rc = dg.main(["evaluate", "--model", str(tmp_path / "nope.pt"), "--maps", "test", "--out", str(tmp_path / "e")])
    assert rc == 2
    assert "does not exist" in capsys.readouterr().err
