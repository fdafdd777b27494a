"""The driving case study's labels (sim4cv.driving_labels, pure) and a tiny
real dataset generation (sim4cv.driving_dataset, the real sim4cvd)."""

import csv
import json
import math
import os
import sys

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_labels as dl  # noqa: E402

STRAIGHT = [(2.0, 0.0), (4.0, 0.0), (6.0, 0.0), (8.0, 0.0)]


def close(got, want, tol=1e-9):
    assert len(got) == len(want)
    for (v, h), (ev, eh) in zip(got, want):
        assert v == pytest.approx(ev, abs=tol) and h == pytest.approx(eh, abs=tol), (got, want)


def test_straight_road_from_the_lane_centre():
    # car at the origin heading east, the points straight ahead
    close(dl.encode(0, 0, 0, STRAIGHT), [(2, 0), (4, 0), (6, 0), (8, 0)])


def test_view_shifted_left_sees_points_to_its_right():
    # the view 1 m to the left of the lane (y = +1 while heading east): every point is 1 m to its right
    close(dl.encode(0, 1, 0, STRAIGHT), [(2, 1), (4, 1), (6, 1), (8, 1)])
    assert dl.steering_angle(*dl.encode(0, 1, 0, STRAIGHT)[0]) > 0  # steer right, as Controls.steering +1
    close(dl.encode(0, -1, 0, STRAIGHT), [(2, -1), (4, -1), (6, -1), (8, -1)])


def test_view_yawed_90_degrees_left():
    # heading north at the origin: the eastern points are all at v = 0, h = x (to the right)
    close(dl.encode(0, 0, math.pi / 2, STRAIGHT), [(0, 2), (0, 4), (0, 6), (0, 8)])
    # and a point north of it is straight ahead
    close(dl.encode(0, 0, math.pi / 2, [(0, 5)]), [(5, 0)])


def test_right_turn_on_a_circle_of_20_m():
    # Heading east at the origin, turning right on a circle of radius R = 20 m about (0, -20).
    # After an arc of length s the turn angle is a = s / R and the point is
    # (R sin a, -R (1 - cos a)); seen from the origin heading east: v = R sin a, h = R (1 - cos a).
    # s = 2: a = 0.1   -> v = 20 * 0.0998334 = 1.996668, h = 20 * 0.0049958 = 0.099917
    # s = 4: a = 0.2   -> v = 20 * 0.1986693 = 3.973387, h = 20 * 0.0199334 = 0.398668
    # s = 6: a = 0.3   -> v = 20 * 0.2955202 = 5.910404, h = 20 * 0.0446635 = 0.893270
    # s = 8: a = 0.4   -> v = 20 * 0.3894183 = 7.788367, h = 20 * 0.0789390 = 1.578779
    r = 20.0
    points = [(r * math.sin(s / r), -r * (1 - math.cos(s / r))) for s in (2, 4, 6, 8)]
    want = [(1.996668, 0.099917), (3.973387, 0.398668), (5.910404, 0.893270), (7.788367, 1.578779)]
    close(dl.encode(0, 0, 0, points), want, tol=1e-5)
    assert all(h > 0 for _, h in dl.encode(0, 0, 0, points))  # a right turn: points to the right


def test_decode_is_the_inverse():
    rng = np.random.default_rng(1)
    for _ in range(50):
        x, y, yaw = rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-4, 4)
        pts = [tuple(p) for p in rng.uniform(-50, 50, size=(4, 2))]
        back = dl.decode(x, y, yaw, dl.encode(x, y, yaw, pts))
        for (px, py), (bx, by) in zip(pts, back):
            assert bx == pytest.approx(px, abs=1e-9) and by == pytest.approx(py, abs=1e-9)


def test_augmented_views_re_encode_the_original_waypoints():
    x, y, yaw = 10.0, -5.0, math.radians(30)
    waypoints = dl.decode(x, y, yaw, [(2, 0), (4, 0), (6, 0), (8, 0)])
    rng = np.random.default_rng(7)
    views = dl.augment_poses(x, y, yaw, "random", rng, n=200)
    assert len(views) == 200
    for vx, vy, vyaw, off_m, off_deg in views:
        assert -4 <= off_m <= 4 and -30 <= off_deg <= 30
        # the view is off_m to the right of the lane pose
        assert dl.encode(x, y, yaw, [(vx, vy)])[0] == pytest.approx((0.0, off_m), abs=1e-9)
        assert vyaw == pytest.approx(yaw + math.radians(off_deg))
        labels = dl.encode(vx, vy, vyaw, waypoints)
        back = dl.decode(vx, vy, vyaw, labels)
        for a, b in zip(back, waypoints):
            assert a == pytest.approx(b, abs=1e-9)
    # a pure sideways shift of +1 m (right), no yaw: the lane is 1 m to the left: h = -1
    (vx, vy, vyaw, _, _), = [v for v in dl.augment_poses(0, 0, 0, "fixed") if v[3] == 1 and v[4] == 0]
    close(dl.encode(vx, vy, vyaw, STRAIGHT), [(2, -1), (4, -1), (6, -1), (8, -1)])
    fixed = dl.augment_poses(x, y, yaw, "fixed")
    assert len(fixed) == 24 and len(dl.all_views(x, y, yaw, "fixed")) == 25
    assert dl.augment_poses(x, y, yaw, "none") == []
    assert dl.all_views(x, y, yaw, "none") == [(x, y, yaw, 0.0, 0.0)]
    with pytest.raises(ValueError):
        dl.augment_poses(x, y, yaw, "sideways")


def test_route_geometry_is_continuous():
    info = dd.parse_map(os.path.join(REPO_ROOT, "scenes", "driving", "train", "01_urban.map"))
    lane = dd.RoutePath(info, "loop")
    prev = lane.point(0.0)
    u = 0.05
    while u <= lane.length + 0.05:
        p = lane.point(u)
        assert math.hypot(p[0] - prev[0], p[1] - prev[1]) == pytest.approx(0.05, abs=1e-3)
        assert abs(dd._wrap(p[2] - prev[2])) < 0.05 / 8 + 1e-6  # tightest bend: radius 8 m
        prev, u = p, u + 0.05


def _generate(out, **kw):
    args = dict(maps=[os.path.join(REPO_ROOT, "scenes", "driving", "val", "01_desert.map")],
                surroundings=["desert"], out=str(out), views="random", random_views=2, max_samples=10,
                log=lambda *a: None)
    args.update(kw)
    return dd.generate(**args)


def test_tiny_generation_resume_and_refusals(tmp_path):
    out = tmp_path / "ds"
    meta = _generate(out)
    name = "driving_val_01_desert"
    assert meta["counts"] == dict(meta["counts"], maps=1, samples=10, images=30)
    assert meta["maps"][name]["complete"] and meta["images_per_s"] > 0
    with open(out / "labels.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == dd.COLUMNS
    assert len(rows) == 30
    for row in rows:
        assert os.path.getsize(out / row["image"]) > 1000
        assert row["map"] == name and row["surroundings"] == "desert" and row["goal"] == "0"
        off_m, off_deg = float(row["offset_side_m"]), float(row["offset_yaw_deg"])
        if off_m == 0 and off_deg == 0:  # the original view on the lane centre
            assert float(row["v1"]) == pytest.approx(2.0, abs=0.05)
            for i in range(1, 5):
                assert abs(float(row["h%d" % i])) < 0.5
        else:
            assert -4 <= off_m <= 4 and -30 <= off_deg <= 30
        v = [float(row["v%d" % i]) for i in range(1, 5)]
        h = [float(row["h%d" % i]) for i in range(1, 5)]
        for i in range(4):  # the waypoints are 2 m apart whatever the view
            if i:
                assert math.hypot(v[i] - v[i - 1], h[i] - h[i - 1]) == pytest.approx(2.0, abs=0.05)
    import cv2
    img = cv2.imread(str(out / rows[0]["image"]))
    assert img.shape == (180, 320, 3)
    assert len([r for r in rows if float(r["offset_side_m"]) == 0 and float(r["offset_yaw_deg"]) == 0]) == 10

    # resume: a complete map is skipped (its images are not touched)
    mtime = os.path.getmtime(out / rows[0]["image"])
    logs = []
    _generate(out, log=logs.append)
    assert any("skipped" in line for line in logs)
    assert os.path.getmtime(out / rows[0]["image"]) == mtime

    # an interrupted map is redone
    with open(out / "dataset.json") as f:
        stored = json.load(f)
    stored["maps"][name]["complete"] = False
    with open(out / "dataset.json", "w") as f:
        json.dump(stored, f)
    (out / "images" / name / "000029.png").unlink()
    meta = _generate(out)
    assert meta["maps"][name]["complete"] and (out / "images" / name / "000029.png").exists()
    with open(out / "labels.csv") as f:
        assert len(list(csv.DictReader(f))) == 30

    # refusal: other settings; nothing is overwritten
    before = (out / "dataset.json").read_bytes(), (out / "labels.csv").read_bytes()
    with pytest.raises(dd.DatasetError, match="other settings"):
        _generate(out, views="fixed")
    assert ((out / "dataset.json").read_bytes(), (out / "labels.csv").read_bytes()) == before
    assert dd.main(["generate", "--maps", "val", "--surroundings", "desert", "--out", str(out),
                    "--max-samples", "1"]) == 2

    # refusal: a folder that cannot be written (under a file; root ignores permission bits)
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    with pytest.raises(dd.DatasetError, match="not writable"):
        _generate(blocker / "ds")
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        with pytest.raises(dd.DatasetError, match="not writable"):
            _generate(ro)


def test_narrow_ranges_render_views_near_the_lane(tmp_path):
    # --offset-range 0.5 --yaw-range 5: views where a driving model is in closed loop
    meta = _generate(tmp_path / "near", offset_range=0.5, yaw_range=5.0)
    assert meta["settings"]["augmentation"]["random_offset_m"] == 0.5
    assert meta["settings"]["augmentation"]["random_yaw_deg"] == 5.0
    with open(tmp_path / "near" / "labels.csv") as f:
        rows = [r for r in csv.DictReader(f) if float(r["offset_side_m"]) or float(r["offset_yaw_deg"])]
    assert len(rows) == 20
    assert all(abs(float(r["offset_side_m"])) <= 0.5 and abs(float(r["offset_yaw_deg"])) <= 5.0 for r in rows)
    with pytest.raises(dd.DatasetError, match=r"--offset-range 5 and --yaw-range 30: within \[0, 4\] m"):
        _generate(tmp_path / "wide", offset_range=5.0)
    # a dataset of other ranges is another dataset
    with pytest.raises(dd.DatasetError, match="other settings"):
        _generate(tmp_path / "near", offset_range=0.25, yaw_range=5.0)


def test_an_ego_car_under_each_view_lights_the_road_at_night_as_in_closed_loop(tmp_path):
    import cv2
    # straight-on views at night, without and with the car under the camera
    plain = _generate(tmp_path / "plain", views="none", max_samples=3, conditions="night")
    lit = _generate(tmp_path / "lit", views="none", max_samples=3, conditions="night", ego_car=True)
    assert "ego_car" not in plain["settings"] and lit["settings"]["ego_car"] is True
    assert lit["maps"]["driving_val_01_desert"]["views_inside_parked_cars"] == 0
    for i in range(3):
        dark, bright = (cv2.imread(str(tmp_path / d / "images" / "driving_val_01_desert" / ("%06d.png" % i)))
                        for d in ("plain", "lit"))
        road = (slice(100, 180), slice(100, 220))  # the road ahead, where the headlights fall
        assert bright[road].mean() > dark[road].mean() + 15, i
        sky = (slice(0, 40), slice(None))
        assert abs(float(bright[sky].mean()) - float(dark[sky].mean())) < 1
    # with parked cars: no view where the car would stand inside one, and the passing views are kept
    parked = _generate(tmp_path / "parked", views="random", random_views=3, max_samples=0, obstacles=2,
                       straight_step=4.0, turn_step=4.0, ego_car=True,
                       maps=[os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")],
                       surroundings=["urban"])
    counts = parked["maps"]["driving_test_01_urban"]
    assert counts["obstacles"] == 2 and counts["views_inside_parked_cars"] >= 1
    assert counts["images"] == 4 * counts["samples"] - counts["views_inside_parked_cars"]
