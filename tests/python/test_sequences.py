"""sim4cv.attributes (each attribute at its threshold's edge, on hand-made
arrays) and sim4cv.sequences (a real generation of tiny sequences from the
real daemon: files, formats, NaN rows, resume; sim4cv.ope reading it all).

Success thresholds t = 0, 0.05, ..., 1 count IoU > t, so the ground truth
evaluated against itself succeeds at 20 of the 21 thresholds (not at t = 1):
success AUC 20/21 per valid frame. Under the OTB convention a frame whose
truth is NaN is a miss at every IoU threshold and a hit at every precision
threshold (centre error -1), so a sequence with k NaN frames of n scores AUC
(n - k)/n * 20/21 and precision 1.
"""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT
from sim4cv import attributes as A
from sim4cv import ope
from sim4cv import sequences as S

NAN4 = [math.nan] * 4
W, H = 320, 180


def boxes(*rows):
    return np.array(rows, dtype=float)


# ----------------------------------------------------------------------------- attributes, per frame


def test_scale_variation_edges_and_first_valid_reference():
    # reference 10x10 = 100 (frame 0 is NaN, so frame 1 is the reference)
    gt = boxes(NAN4, [0, 0, 10, 10], [0, 0, 20, 10], [0, 0, 20.1, 10], [0, 0, 5, 10], [0, 0, 4.9, 10], NAN4)
    assert A.scale_variation(gt).tolist() == [False, False, False, True, False, True, False]


def test_aspect_ratio_change_edges():
    gt = boxes([0, 0, 10, 10], [0, 0, 20, 10], [0, 0, 21, 10], [0, 0, 10, 20], [0, 0, 10, 21])
    assert A.aspect_ratio_change(gt).tolist() == [False, False, True, False, True]


def test_low_resolution_below_400_pixels():
    gt = boxes([0, 0, 20, 20], [0, 0, 19, 21], NAN4)
    assert A.low_resolution(gt).tolist() == [False, True, False]


def test_size_boxes_use_the_unoccluded_extent():
    # an occluded frame's visible box is small, its extent is not: no SV, no LR
    gt = boxes([0, 0, 20, 40], [0, 0, 5, 10], NAN4)
    extent = boxes([0, 0, 20, 40], [0, 0, 20, 40], [0, 0, 20, 40])
    sized = A.size_boxes(gt, extent)
    assert not A.scale_variation(sized).any() and not A.low_resolution(sized).any()
    assert np.isnan(sized[2]).all()
    flags = A.per_frame(gt, (W, H), visibility=[1, 0.2, 0], extent=extent)
    assert flags["SV"].tolist() == [False, False, False] and flags["LR"].tolist() == [False, False, False]
    assert A.scale_variation(gt).tolist() == [False, True, False]  # on the visible boxes it would be


def test_fast_motion_more_than_20_px_between_consecutive_boxes():
    gt = boxes([0, 0, 10, 10], [20, 0, 10, 10], [40.5, 0, 10, 10], NAN4, [100, 0, 10, 10], [100, 0, 10, 10])
    # moves: 20 (no), 20.5 (yes), to/from NaN (no), 0 (no)
    assert A.fast_motion(gt).tolist() == [False, False, True, False, False, False]


def test_occlusion_from_visibility():
    gt = boxes([0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10], NAN4, NAN4)
    vis = [1.0, 0.9, 0.89, 0.0, 0.0]
    in_view = [True, True, True, True, False]
    assert A.partial_occlusion(gt, vis).tolist() == [False, False, True, False, False]
    assert A.full_occlusion(gt, vis, in_view).tolist() == [False, False, False, True, False]


def test_out_of_view_box_touches_an_edge_or_target_out_of_view():
    gt = boxes([0, 50, 10, 10], [1, 50, 10, 10], [W - 10, 50, 10, 10], [W - 11, 50, 10, 10],
               [50, 0, 10, 10], [50, H - 10, 10, 10], [50, H - 11, 10, 10], NAN4)
    in_view = [True] * 7 + [False]
    assert A.out_of_view(gt, (W, H), in_view).tolist() == [True, False, True, False, True, True, False, True]


def test_background_clutter_histogram_similarity():
    img = np.zeros((60, 60, 3), np.uint8)
    img[:] = (0, 0, 255)
    img[20:40, 20:40] = (255, 0, 0)           # red target on blue: nothing in common
    luma, sim = A.box_measures(img, (20, 20, 20, 20))
    assert sim == 0.0 and luma == pytest.approx(0.299 * 255)
    img[:] = (250, 0, 0)                      # red on (the same bin of) red: identical histograms
    assert A.box_measures(img, (20, 20, 20, 20))[1] == pytest.approx(1.0)
    # with a target mask only the target's own pixels count for the luma
    img[:] = 0
    img[20:30, 20:40] = 200
    mask = np.zeros((60, 60), bool)
    mask[20:30, 20:40] = True
    assert A.box_measures(img, (20, 20, 20, 20), mask)[0] == pytest.approx(200.0)
    assert A.box_measures(img, (20, 20, 20, 20))[0] == pytest.approx(100.0)
    assert math.isnan(A.box_measures(img, None)[0])
    t = A.THRESHOLDS["bc_similarity"]
    gt = boxes([0, 0, 10, 10], [0, 0, 10, 10], NAN4)
    assert A.background_clutter(gt, [t, t + 0.01, 0.99]).tolist() == [False, True, False]


def test_illumination_variation_ratio_and_dark_presets():
    gt = boxes(*[[0, 0, 10, 10]] * 5)
    luma = [100.0, 150.0, 151.0, 100 / 1.5 + 1e-9, 66.0]
    assert A.illumination_variation(gt, luma).tolist() == [False, False, True, False, True]
    assert A.illumination_variation(gt, [100.0] * 5, conditions="night").all()
    assert not A.illumination_variation(gt, [100.0] * 5, conditions="overcast").any()
    assert A.illumination_variation(gt, [100.0] * 5, change_every=2).tolist() == [False, False, True, False, True]


def test_viewpoint_change_more_than_30_degrees():
    # camera 10 m behind the target, turned around it by 0, 29.9 and 30.1 degrees
    angles = np.radians([0.0, 29.9, 30.1, 180.0])
    cam = np.stack([-10 * np.cos(angles), -10 * np.sin(angles), np.zeros(4)], axis=1)
    assert A.viewpoint_change(cam, np.zeros((4, 3)), np.zeros(4)).tolist() == [False, False, True, True]
    # the target turning under a fixed camera is the same change
    yaws = -angles
    cam0 = np.tile([-10.0, 0.0, 0.0], (4, 1))
    assert A.viewpoint_change(cam0, np.zeros((4, 3)), yaws).tolist() == [False, False, True, True]


def test_camera_motion_faster_than_30_degrees_per_second():
    def yaw_quat(deg):
        r = math.radians(deg) / 2
        return [math.cos(r), 0.0, 0.0, math.sin(r)]
    # at 30 Hz: steps of 0.9, 1.1 and 0 degrees (27, 33 and 0 deg/s)
    q = [yaw_quat(d) for d in (0.0, 0.9, 2.0, 2.0)]
    assert A.camera_motion(q, 30.0).tolist() == [False, False, True, False]


def test_similar_object_within_two_target_sizes():
    target = (100, 100, 10, 20)                  # size max(w, h) = 20, centre (105, 110)
    assert A.similar_object_distance(target, [(100, 140, 10, 20)]) == pytest.approx(2.0)
    assert A.similar_object_distance(target, [(100, 139, 10, 20), (0, 0, 5, 5)]) == pytest.approx(1.95)
    assert math.isnan(A.similar_object_distance(target, []))
    gt = boxes([0, 0, 10, 10], [0, 0, 10, 10], [0, 0, 10, 10])
    assert A.similar_object(gt, [2.0, 1.95, math.nan]).tolist() == [False, True, False]


def test_per_sequence_rules_and_files(tmp_path):
    n = 100
    flags = {a: np.zeros(n, bool) for a in A.ABBREVS}
    flags["SV"][7] = True              # one frame is enough (UAV123's "at least one")
    flags["POC"][:4] = True            # 4 % < 5 %
    flags["CM"][:5] = True             # 5 %
    seq = A.per_sequence(flags)
    assert seq["SV"] and not seq["POC"] and seq["CM"] and not seq["FOC"]
    A.write_attribute_names(str(tmp_path))
    seq_dir = tmp_path / "s"
    seq_dir.mkdir()
    A.write_attributes(str(seq_dir), flags)
    names = ope.read_attribute_names(str(tmp_path / "attribute_names.txt"))
    assert [a for a, _ in names] == A.ABBREVS and names[0] == ("SV", "Scale Variation")
    got = ope.read_sequence_attributes(str(seq_dir), names, [])
    assert got == seq
    (seq_dir / "attributes.txt").unlink()  # the per-frame file says "any frame"
    got = ope.read_sequence_attributes(str(seq_dir), names, [])
    assert got["POC"] and got["SV"] and not got["FOC"]
    rows = (seq_dir / "attributes_per_frame.csv").read_text().splitlines()
    assert rows[0] == ",".join(A.ABBREVS) and len(rows) == n + 1


def test_lap_counter_counts_circles():
    laps = S.LapCounter()
    for i in range(0, 2 * 360 + 10):          # 2 laps and a bit of a 50 m circle, 1 degree a step
        a = math.radians(i)
        done = laps.update(50 * math.sin(a), 50 - 50 * math.cos(a), a)
    assert done == 2


# ----------------------------------------------------------------------------- generation with the daemon


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.path.join(REPO_ROOT, "clients", "python") + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "sim4cv.sequences"] + list(args), env=_env(), cwd=REPO_ROOT,
                          capture_output=True, text=True, timeout=120)


def _check_sequence(seq_dir, frames):
    import cv2
    meta = json.loads(open(os.path.join(seq_dir, "sequence.json")).read())
    assert meta["complete"] and meta["frames"] == frames
    assert meta["camera_intrinsics"]["width"] == W and meta["camera_intrinsics"]["height"] == H
    assert meta["daemon_version"] and meta["frame_hz"] == 30.0 and meta["target_id"] == 1
    imgs = sorted(os.listdir(os.path.join(seq_dir, "img")))
    assert imgs == ["%06d.jpg" % i for i in range(1, frames + 1)]
    assert cv2.imread(os.path.join(seq_dir, "img", imgs[0])).shape == (H, W, 3)
    lines = open(os.path.join(seq_dir, "groundtruth_rect.txt")).read().splitlines()
    assert len(lines) == frames
    for line in lines:
        v = line.split(",")
        assert len(v) == 4 and (v == ["NaN"] * 4 or all(s.isdigit() for s in v)), line
    poses = open(os.path.join(seq_dir, "poses.csv")).read().splitlines()
    assert poses[0].split(",") == S.POSES_HEADER and len(poses) == frames + 1
    assert len(open(os.path.join(seq_dir, "measures.csv")).read().splitlines()) == frames + 1
    flags = open(os.path.join(seq_dir, "attributes.txt")).read().split()
    assert len(flags) == 1 and len(flags[0].split(",")) == len(A.ABBREVS)
    return meta, lines


def test_generate_resume_and_ope(tmp_path, start_daemon):
    out = str(tmp_path / "seqs")
    # 1. the CLI with its own daemon: 20 frames of the easy desert map at 8 m/s, with depth and mask
    r = _cli("generate", "--out", out, "--maps", "tracking/easy_desert", "--speeds", "8", "--frames", "20",
             "--channels", "depth,mask")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "images/s" in r.stdout
    seq = os.path.join(out, "easy_desert_s8")
    meta, lines = _check_sequence(seq, 20)
    assert meta["speed"] == 8.0 and meta["map"] == "tracking/easy_desert" and meta["seed"] == 1
    assert meta["conditions"]["preset"] == "clear_noon"
    assert "NaN" not in lines[0]
    depth = np.load(os.path.join(seq, "depth", "000001.npy"))
    assert depth.shape == (H, W) and depth.dtype == np.float32
    import cv2
    mask = cv2.imread(os.path.join(seq, "mask", "000001.png"), cv2.IMREAD_UNCHANGED)
    assert mask.dtype == np.uint16 and (mask == 1).sum() == int(open(os.path.join(seq, "poses.csv"))
                                                                 .read().splitlines()[1].split(",")[15])
    # the box is the tight box of the target's mask pixels: [x, x+w) x [y, y+h)
    x, y, w, h = (int(v) for v in lines[0].split(","))
    rows, cols = np.nonzero(mask == 1)
    assert (cols.min(), rows.min(), cols.max() + 1 - cols.min(), rows.max() + 1 - rows.min()) == (x, y, w, h)
    names = open(os.path.join(out, "attribute_names.txt")).read().splitlines()
    assert [n.split("\t")[0] for n in names] == A.ABBREVS

    # 2. resume: a complete sequence is skipped (its files are not rewritten) ...
    stamp = os.stat(os.path.join(seq, "img", "000001.jpg")).st_mtime_ns
    r = _cli("generate", "--out", out, "--maps", "easy_desert", "--speeds", "8", "--frames", "20",
             "--channels", "depth,mask")
    assert r.returncode == 0 and "skipped" in r.stdout, r.stdout + r.stderr
    assert os.stat(os.path.join(seq, "img", "000001.jpg")).st_mtime_ns == stamp
    # ... a partial one is generated again
    meta["complete"] = False
    with open(os.path.join(seq, "sequence.json"), "w") as f:
        json.dump(meta, f)
    open(os.path.join(seq, "img", "000999.jpg"), "w").close()
    r = _cli("generate", "--out", out, "--maps", "easy_desert", "--speeds", "8", "--frames", "20",
             "--channels", "depth,mask")
    assert r.returncode == 0 and "regenerating" in r.stdout, r.stdout + r.stderr
    _check_sequence(seq, 20)

    # 3. a running daemon (--daemon): the generator loads the map; the UAV is made to
    # spin away from the car, so the last frames have no box (NaN rows, OV)
    daemon = start_daemon()

    def spin(client, index, frame):
        if index == 1:
            client.uav_velocity(2, 0.0, 0.0, 0.0, yaw_rate_deg=180.0)

    spec = S.Spec("hard_urban", 6, frames=S_SPIN_FRAMES, name="hard_urban_s6_spin", camera_motion="servo")
    got = S.generate_sequence(spec, out, daemon="tcp://127.0.0.1:%d" % daemon.port, frame_hook=spin,
                              log=lambda text: None)
    assert got["daemon"].startswith("tcp://") and got["seed"] is None and got["map_name"] == "tracking_hard_urban"
    spun = os.path.join(out, "hard_urban_s6_spin")
    _, spun_lines = _check_sequence(spun, S_SPIN_FRAMES)
    absent = [line.startswith("NaN") for line in spun_lines]
    assert not absent[0] and absent[-1], spun_lines
    per_frame = open(os.path.join(spun, "attributes_per_frame.csv")).read().splitlines()
    ov, ta = A.ABBREVS.index("OV"), A.ABBREVS.index("TA")
    last = per_frame[-1].split(",")
    assert last[ov] == "1" and last[ta] == "1"
    poses = A._read_csv(os.path.join(spun, "poses.csv"))
    assert (poses["target_visibility"][np.array(absent)] == 0).all()

    # 4. ope reads it all: the ground truth as a tracker's result
    res = tmp_path / "results" / "gt"
    res.mkdir(parents=True)
    for name in ("easy_desert_s8", "hard_urban_s6_spin"):
        (res / (name + ".txt")).write_text(open(os.path.join(out, name, "groundtruth_rect.txt")).read())
    report_dir = tmp_path / "ope"
    r = subprocess.run([sys.executable, "-m", "sim4cv.ope", "--sequences", out, "--results",
                        str(tmp_path / "results"), "--out", str(report_dir), "--require-all"],
                       env=_env(), cwd=REPO_ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads((report_dir / "ope.json").read_text())
    per_seq = report["trackers"]["gt"]["per_sequence"]
    assert per_seq["easy_desert_s8"]["success_auc"] == pytest.approx(20 / 21)
    assert per_seq["easy_desert_s8"]["precision_20"] == 1.0
    k, n = sum(absent), len(absent)
    assert per_seq["hard_urban_s6_spin"]["success_auc"] == pytest.approx((n - k) / n * 20 / 21)
    assert per_seq["hard_urban_s6_spin"]["precision_20"] == 1.0
    assert report["trackers"]["gt"]["precision_20"] == 1.0
    assert set(report["attributes"]) == set(A.ABBREVS)
    assert "hard_urban_s6_spin" in report["attributes"]["OV"]["sequences"]
    for name in ("easy_desert_s8", "hard_urban_s6_spin"):
        flags = open(os.path.join(out, name, "attributes.txt")).read().strip().split(",")
        for abbrev, flag in zip(A.ABBREVS, flags):
            assert (name in report["attributes"][abbrev]["sequences"]) == (flag == "1")
    # got10k leaves the NaN frames out: the ground truth scores 20/21 on both
    r = subprocess.run([sys.executable, "-m", "sim4cv.ope", "--sequences", out, "--results",
                        str(tmp_path / "results"), "--out", str(tmp_path / "ope10k"), "--convention", "got10k"],
                       env=_env(), cwd=REPO_ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads((tmp_path / "ope10k" / "ope.json").read_text())
    assert report["trackers"]["gt"]["success_auc"] == pytest.approx(20 / 21)

    # 5. the attribute files can be recomputed from the folders alone
    before = open(os.path.join(spun, "attributes_per_frame.csv")).read()
    S.recompute_attributes(out, log=lambda text: None)
    assert open(os.path.join(spun, "attributes_per_frame.csv")).read() == before


S_SPIN_FRAMES = 45


def test_cli_rejects_bad_arguments_and_lists_maps():
    r = _cli("maps")
    assert r.returncode == 0 and r.stdout.split() == S.TRACKING_MAPS
    r = _cli("generate", "--out", "/nonexistent/x", "--channels", "colour")
    assert r.returncode == 2 and "--channels" in r.stderr
    r = _cli("generate", "--out", "/nonexistent/x", "--preset", "paper", "--frames", "20")
    assert r.returncode == 2 and "preset" in r.stderr


def test_paper_preset_is_five_sequences_of_the_two_layouts_at_three_speeds():
    specs = S.paper_specs()
    assert len(specs) == 5 and len({s.name for s in specs}) == 5
    assert {s.map.split("/")[1].split("_")[0] for s in specs} == {"easy", "hard"}
    assert {s.speed for s in specs} == {4.0, 6.0, 8.0}
    assert all(s.laps >= 1 and s.frames == 0 for s in specs)
