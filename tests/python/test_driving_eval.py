"""The driving score (sim4cv.driving_metrics) on hand-computed cases, and
the closed-loop evaluation (sim4cv.driving_eval) with a real sim4cvd: the
reference policy drives a whole test map; bad model files are refused."""

import json
import math
import os
import subprocess
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_control as dc  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_eval as de  # noqa: E402
from sim4cv import driving_metrics as dm  # noqa: E402

TEST_MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_desert.map")


def test_departures_count_each_crossing_of_the_lane_edge_once():
    assert dm.departures([0.0, 0.5, 1.2, 1.5, 0.3, -1.1, -0.2]) == 2
    assert dm.departures([1.5, 1.5, 0.0]) == 1  # starting beyond counts
    assert dm.departures([1.0, -1.0]) == 0      # exactly at the edge is still inside


def test_score_and_cumulative_histogram_by_hand():
    deviations = [0.0, -0.04, 0.06, 0.2, 0.3, -0.6, 1.2, 0.0]
    s = dm.score(deviations, distance_m=12.5, collisions=1)
    assert s["samples"] == 8
    assert s["mean_deviation_cm"] == pytest.approx(100 * (0.04 + 0.06 + 0.2 + 0.3 + 0.6 + 1.2) / 8, abs=1e-3)
    assert s["max_deviation_cm"] == pytest.approx(120.0)
    assert s["within_25cm"] == pytest.approx(5 / 8)
    assert s["within_50cm"] == pytest.approx(6 / 8)
    assert s["within_1m"] == pytest.approx(7 / 8)
    assert s["lane_departures"] == 1 and s["collisions"] == 1 and s["distance_m"] == 12.5
    edges, fractions = dm.cumulative_histogram(deviations)
    assert len(edges) == 20 and edges[0] == 0.05 and edges[-1] == 1.0
    assert fractions[0] == pytest.approx(3 / 8)   # 0, 0.04, 0
    assert fractions[1] == pytest.approx(4 / 8)   # + 0.06
    assert fractions[3] == pytest.approx(5 / 8)   # + 0.2 (exactly on the edge)
    assert fractions[-1] == pytest.approx(7 / 8)


def test_pooled_weighs_runs_by_time():
    a = dm.score([0.1, 0.1, 0.1], 10)
    b = dm.score([0.3], 5)
    p = dm.pooled([a, b], [[0.1, 0.1, 0.1], [0.3]])
    assert p["mean_deviation_cm"] == pytest.approx(15.0)
    assert p["distance_m"] == 15 and p["runs"] == 2


def test_signed_distance_is_positive_to_the_right():
    east = (0.0, 10.0, "line", ((0.0, 0.0), 0.0))
    assert dm.signed_distance_to_segment(5.0, -1.0, east) == pytest.approx((5.0, 1.0))
    assert dm.signed_distance_to_segment(5.0, 2.0, east) == pytest.approx((5.0, -2.0))
    # a left turn (ccw) of radius 10 about (0, 10), entered at (0, 0) heading east
    left = (0.0, 10 * math.pi / 2, "arc", (0.0, 10.0, 10.0, -math.pi / 2, 1.0))
    s, d = dm.signed_distance_to_segment(0.0, -0.5, left)  # 0.5 m outside the circle: right of travel
    assert s == pytest.approx(0.0, abs=1e-9) and d == pytest.approx(0.5)
    s, d = dm.signed_distance_to_segment(10 * math.sin(0.3) * 0.9, 10 - 10 * math.cos(0.3) * 0.9, left)
    assert s == pytest.approx(3.0) and d == pytest.approx(-1.0)  # inside the turn: left


def test_progress_follows_the_lane_of_a_real_route():
    info = dd.parse_map(TEST_MAP)
    path = dd.RoutePath(info, next(iter(info["routes"])))
    progress = dm.Progress(path, 0.0)
    for u in [0.5 * i for i in range(int(path.length * 2.2))]:  # more than two laps
        x, y, heading = path.point(u)
        # 0.3 m to the right of the lane centre
        d = progress.update(x + 0.3 * math.sin(heading), y - 0.3 * math.cos(heading))
        assert d == pytest.approx(0.3, abs=1e-6)
        assert progress.u == pytest.approx(u, abs=1e-6)


def test_collisions_count_each_contact_once():
    c = dm.Collisions([("tree", 10.0, 0.0, 0.0), ("park", 0.0, 0.0, 0.0), ("house", 40.0, 0.0, 0.0)])
    assert len(c.objects) == 2  # parks are flat
    assert c.update(0.0, 0.0, 0.0) == 0
    assert c.update(7.6, 0.0, 0.0) == 1   # bumper 2.25 m ahead reaches the trunk (0.3 m)
    assert c.update(7.7, 0.0, 0.0) == 0   # still touching: not a new one
    assert c.update(0.0, 0.0, 0.0) == 0
    assert c.update(10.0, 1.1, 0.0) == 1  # side (0.9 m) against the trunk
    assert c.update(33.0, 0.0, 0.0) == 1  # the house's 5 m half-length
    assert c.count == 3


def test_reference_policy_drives_a_test_map_within_the_lane(tmp_path):
    report = de.evaluate(de.ReferencePolicy(), [TEST_MAP], ["desert"], str(tmp_path), log=lambda *a: None)
    with open(tmp_path / "driving.json") as f:
        assert json.load(f)["overall"] == report["overall"]
    o = report["overall"]
    assert o["runs"] == 1 and o["completed"] == 1
    assert o["mean_deviation_cm"] < 5.0 and o["within_25cm"] > 0.99
    assert o["lane_departures"] == 0 and o["collisions"] == 0
    run = next(iter(report["maps"]["driving_test_01_desert"]["routes"].values()))
    assert run["distance_m"] == pytest.approx(run["lap_m"], abs=0.01)
    assert (tmp_path / "histogram.png").stat().st_size > 1000
    assert (tmp_path / "trajectories" / "driving_test_01_desert.png").is_file()
    assert report["histogram"]["overall"][4] > 0.99  # within 25 cm


def test_a_left_lane_lap_is_scored_against_the_left_lane(tmp_path):
    # The reference policy aims at the ideal path's points: with lane "left"
    # the lap starts on the left lane and that lane's centre is the path.
    policy = de.ReferencePolicy()
    policy.lane = "left"
    report = de.evaluate(policy, [TEST_MAP], ["desert"], str(tmp_path), log=lambda *a: None)
    o = report["overall"]
    assert o["completed"] == 1 and o["mean_deviation_cm"] < 5.0 and o["lane_departures"] == 0
    csv_path = tmp_path / "runs" / "driving_test_01_desert_loop.csv"
    info = dd.parse_map(TEST_MAP)
    lane = dd.RoutePath(info, "loop")
    rows = [line.split(",") for line in csv_path.read_text().splitlines()[1:]]
    x, y = float(rows[len(rows) // 2][1]), float(rows[len(rows) // 2][2])
    distances = [dm.signed_distance_to_segment(x, y, segment)[1] for segment in lane.segments]
    assert min(distances, key=abs) == pytest.approx(-4.0, abs=0.3)  # 4 m left of the right lane


def test_the_mirror_trick_mirrors_image_goal_and_h():
    pytest.importorskip("torch")
    import numpy as np
    image = np.random.default_rng(2).integers(0, 256, (180, 320, 3), dtype=np.uint8)
    left = de.NetworkPolicy(os.path.join(SHIPPED, "model.pt"), goal=1.0, lane="left")
    right = de.NetworkPolicy(os.path.join(SHIPPED, "model.pt"), goal=-1.0)
    mirrored = right.waypoints(np.ascontiguousarray(image[:, ::-1]), None, None)
    assert left.waypoints(image, None, None) == pytest.approx([-v if i % 2 else v for i, v in enumerate(mirrored)],
                                                              abs=1e-4)


def test_missing_and_malformed_models_are_refused(tmp_path):
    with pytest.raises(de.EvalError, match="model file .*nothing.onnx does not exist"):
        de.NetworkPolicy(str(tmp_path / "nothing.onnx"))
    bad = tmp_path / "garbage.onnx"
    bad.write_bytes(b"not a model")
    with pytest.raises(de.EvalError, match="not a readable ONNX model"):
        de.NetworkPolicy(str(bad))
    text = tmp_path / "model.txt"
    text.write_text("x")
    with pytest.raises(de.EvalError, match=r"expected a \.pt .* or \.onnx"):
        de.NetworkPolicy(str(text))


def test_a_model_of_the_wrong_shape_is_refused_naming_both_shapes(tmp_path):
    torch = pytest.importorskip("torch")
    path = str(tmp_path / "four.onnx")
    torch.onnx.export(torch.nn.Sequential(torch.nn.Flatten(), torch.nn.Linear(3 * 8 * 8, 4)),
                      torch.zeros(1, 3, 8, 8), path, input_names=["image"], output_names=["waypoints"])
    with pytest.raises(de.EvalError, match=r"expected input \[1, 3, H, W\] and output \[1, 8\].*found input "
                                           r"\[1, 3, 8, 8\] and output \[1, 4\]"):
        de.NetworkPolicy(path)
    r = subprocess.run([sys.executable, "-m", "sim4cv.driving", "evaluate", "--model", path, "--out",
                        str(tmp_path / "ev")], cwd=os.path.join(REPO_ROOT, "clients", "python"),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "output [1, 4]" in r.stderr


SHIPPED = os.path.join(REPO_ROOT, "models", "driving")


def test_the_shipped_model_loads_in_both_runtimes_and_agrees():
    pytest.importorskip("torch")
    import numpy as np
    onnx_policy = de.NetworkPolicy(os.path.join(SHIPPED, "model.onnx"))
    torch_policy = de.NetworkPolicy(os.path.join(SHIPPED, "model.pt"))
    assert (onnx_policy.height, onnx_policy.width, onnx_policy.use_goal) == (90, 160, True)
    assert (torch_policy.height, torch_policy.width, torch_policy.use_goal) == (90, 160, True)
    image = np.random.default_rng(1).integers(0, 256, (180, 320, 3), dtype=np.uint8)
    for goal in (-1.0, 0.0, 1.0):
        onnx_policy.goal = torch_policy.goal = goal
        a, b = onnx_policy.waypoints(image, None, None), torch_policy.waypoints(image, None, None)
        assert a == pytest.approx(b, abs=1e-3)


def test_the_shipped_model_drives_a_lap_of_a_test_map(tmp_path):
    # test/01_urban: a lap of 355 m with a left turn at a crossroads (the goal input says left)
    policy = de.NetworkPolicy(os.path.join(SHIPPED, "model.onnx"))
    policy.path = "model.onnx"
    report = de.evaluate(policy, [os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")], ["urban"],
                         str(tmp_path), controller=dc.Controller(steer_waypoint=2), log=lambda *a: None)
    o = report["overall"]
    assert o["completed"] == 1 and o["mean_deviation_cm"] < 30.0 and o["within_1m"] > 0.97


def test_a_lap_over_udp_is_the_lap_over_tcp_frame_for_frame(tmp_path):
    # frames, Steps and Controls on one UDP socket, lockstep: every frame's
    # pose, deviation and controls equal those of the TCP lap, exactly
    policy = de.NetworkPolicy(os.path.join(SHIPPED, "model.onnx"))
    lap = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")
    reports = {t: de.evaluate(policy, [lap], ["urban"], str(tmp_path / t), controller=dc.Controller(2, 0.9),
                              log=lambda *a: None, transport=t) for t in ("tcp", "udp")}
    assert reports["udp"]["settings"]["transport"] == "udp"
    rows = {t: (tmp_path / t / "runs" / "driving_test_01_urban_loop.csv").read_text() for t in reports}
    assert rows["udp"].count("\n") > 1000 and rows["udp"] == rows["tcp"]
    assert reports["udp"]["overall"] == reports["tcp"]["overall"]
    with pytest.raises(de.EvalError, match="transport 'shm': one of tcp, udp"):
        de.evaluate(policy, [lap], ["urban"], str(tmp_path / "shm"), transport="shm")
