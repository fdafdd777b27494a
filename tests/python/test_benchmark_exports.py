"""Exports the field's loaders read as they are, checked with those loaders'
own conventions (got-10k/toolkit's datasets/uav123.py, got10k.py and
experiments/otb.py; pytracking's uavdataset.py and got10kdataset.py: the
checks are ours, written from reading them), plus the baseline trackers and
got10k's per-frame speed, against hand-computed values."""

import configparser
import csv
import glob
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT
from sim4cv import attributes as A
from sim4cv import sequence_export as X
from sim4cv import trackers as T

W, H = 32, 18
# 0-based boxes of our generator; frame 3 has no visible pixel
TRUTH = ["4,5,10,6", "6,5,10,7", "NaN,NaN,NaN,NaN", "0,2,8,6"]
VISIBILITY = [1.0, 0.5, 0.0, 0.3]


def _sequence(root, name):
    import cv2
    seq = os.path.join(root, name)
    os.makedirs(os.path.join(seq, "img"))
    for i in range(1, len(TRUTH) + 1):
        cv2.imwrite(os.path.join(seq, "img", "%06d.jpg" % i), np.full((H, W, 3), 10 * i, np.uint8))
    with open(os.path.join(seq, "groundtruth_rect.txt"), "w") as f:
        f.write("\n".join(TRUTH) + "\n")
    with open(os.path.join(seq, "poses.csv"), "w") as f:
        f.write("frame,target_visibility\n" + "".join("%d,%g\n" % (i + 1, v) for i, v in enumerate(VISIBILITY)))
    with open(os.path.join(seq, "attributes_per_frame.csv"), "w") as f:
        w = csv.writer(f)
        w.writerow(A.ABBREVS)
        for i in range(len(TRUTH)):
            w.writerow([1 if (a == "OV" and i == 3) or (a == "TA" and i == 2) else 0 for a in A.ABBREVS])
    flags = [1 if a in ("OV", "TA", "SV") else 0 for a in A.ABBREVS]
    with open(os.path.join(seq, "attributes.txt"), "w") as f:
        f.write(",".join(map(str, flags)) + "\n")
    with open(os.path.join(seq, "sequence.json"), "w") as f:
        json.dump({"image_size": [W, H], "map": "tracking/easy_urban", "speed": 8.0, "complete": True}, f)
    return seq


@pytest.fixture
def sequences(tmp_path):
    root = str(tmp_path / "seqs")
    for name in ("alpha_s8", "beta_s4"):
        _sequence(root, name)
    return root


def _cli(*args):
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO_ROOT, "clients", "python"))
    return subprocess.run([sys.executable, "-m", "sim4cv.sequences"] + list(args), env=env, cwd=REPO_ROOT,
                          capture_output=True, text=True, timeout=120)


ONE_BASED = np.array([[5, 6, 10, 6], [7, 6, 10, 7], [np.nan] * 4, [1, 3, 8, 6]])


def test_uav123_export_loads_as_the_uav123_loaders_read_it(sequences, tmp_path):
    out = str(tmp_path / "uav123")
    r = _cli("export", sequences, "--format", "uav123", "--out", out)
    assert r.returncode == 0, r.stderr
    # got10k UAV123: names from anno/UAV123/*.txt, images data_seq/UAV123/<name>/%06d.jpg from frame 1,
    # np.loadtxt(anno, delimiter=','), one row per image, 4 columns; pytracking the same paths (nz 6, jpg)
    anno_files = sorted(glob.glob(os.path.join(out, "anno/UAV123/*.txt")))
    names = [os.path.basename(f)[:-4] for f in anno_files]
    assert names == ["alpha_s8", "beta_s4"]
    for name, anno_file in zip(names, anno_files):
        anno = np.loadtxt(anno_file, delimiter=",")
        images = [os.path.join(out, "data_seq/UAV123/%s" % name, "%06d.jpg" % f) for f in range(1, len(anno) + 1)]
        assert all(os.path.isfile(p) for p in images) and len(images) == len(anno) == 4
        assert anno.shape[1] == 4
        np.testing.assert_array_equal(anno, ONE_BASED)  # 1-based, NaN rows kept
        att = open(os.path.join(out, "anno/UAV123/att", name + ".txt")).read().strip().split(",")
        assert att == ["1", "0", "0", "0", "0", "0", "1", "0", "0", "0", "0", "0"]  # SV, OV of UAV123's 12
        absent = np.loadtxt(os.path.join(out, "anno/UAV123/absent", name + ".txt"))
        assert absent.tolist() == [0, 0, 1, 0]


def test_got10k_export_loads_as_the_got10k_loaders_read_it(sequences, tmp_path):
    out = str(tmp_path / "got10k")
    assert X.export(sequences, "got10k", out) is None
    # got10k GOT10k(root, subset='val', return_meta=True): list.txt, sorted *.jpg, groundtruth.txt
    # (np.loadtxt, ','), meta_info.ini (first line skipped, 'key: value'), cover/absence/cut_by_image.label
    with open(os.path.join(out, "val", "list.txt")) as f:
        names = f.read().strip().split("\n")
    assert names == ["alpha_s8", "beta_s4"]
    for name in names:
        seq_dir = os.path.join(out, "val", name)
        images = sorted(glob.glob(os.path.join(seq_dir, "*.jpg")))
        anno = np.loadtxt(os.path.join(seq_dir, "groundtruth.txt"), delimiter=",")
        assert len(images) == len(anno) == 4
        np.testing.assert_array_equal(anno, ONE_BASED)
        # pytracking sorts the frames by int(name[:-4])
        frames = sorted((f for f in os.listdir(seq_dir) if f.endswith(".jpg")), key=lambda f: int(f[:-4]))
        assert frames[0] == "00000001.jpg" and [os.path.join(seq_dir, f) for f in frames] == images
        with open(os.path.join(seq_dir, "meta_info.ini")) as f:
            meta = dict(line.split(": ") for line in f.read().strip().split("\n")[1:])
        assert meta["object_class"] == "car" and meta["end_frame"] == "4" and meta["resolution"] == "(32, 18)"
        assert configparser.ConfigParser().read(os.path.join(seq_dir, "meta_info.ini"))
        labels = {a: np.loadtxt(os.path.join(seq_dir, a + ".label")) for a in ("cover", "absence", "cut_by_image")}
        assert labels["absence"].tolist() == [0, 0, 1, 0]
        assert labels["cover"].tolist() == [8, 4, 0, 3]  # visible 1, 0.5, 0, 0.3 in eighths, rounded up
        assert labels["cut_by_image"].tolist() == [0, 0, 0, 1]


def test_otb_export_and_results_in_got10k_and_pytracking_layouts(sequences, tmp_path):
    out = str(tmp_path / "otb")
    X.export(sequences, "otb", out)
    # got10k OTB: sorted img/*.jpg, groundtruth*.txt read with np.loadtxt(',')
    images = sorted(glob.glob(os.path.join(out, "alpha_s8", "img", "*.jpg")))
    assert [os.path.basename(p) for p in images] == ["0001.jpg", "0002.jpg", "0003.jpg", "0004.jpg"]
    np.testing.assert_array_equal(np.loadtxt(os.path.join(out, "alpha_s8", "groundtruth_rect.txt"), delimiter=","),
                                  ONE_BASED)
    results = tmp_path / "results" / "opencv_kcf"
    results.mkdir(parents=True)
    (results / "alpha_s8.txt").write_text("4.00,5.00,10.00,6.00\nNaN,NaN,NaN,NaN\n1.50,2.25,3.00,4.00\n")
    (results / "alpha_s8_time.txt").write_text("0.100000\n0.010000\n0.020000\n")
    r = _cli("export-results", str(tmp_path / "results"), "--layout", "got10k", "--out", str(tmp_path / "g"))
    assert r.returncode == 0, r.stderr
    # got10k ExperimentOTB.report: <tracker>/<seq>.txt with ',' and <tracker>/times/<seq>_time.txt
    boxes = np.loadtxt(str(tmp_path / "g" / "opencv_kcf" / "alpha_s8.txt"), delimiter=",")
    np.testing.assert_array_equal(boxes, [[5, 6, 10, 6], [np.nan] * 4, [2.5, 3.25, 3, 4]])
    times = np.loadtxt(str(tmp_path / "g" / "opencv_kcf" / "times" / "alpha_s8_time.txt"))
    assert times.tolist() == [0.1, 0.01, 0.02]
    # pytracking: tab-separated <seq>.txt and <seq>_time.txt beside it
    X.export_results(str(tmp_path / "results"), "pytracking", str(tmp_path / "p"))
    boxes = np.loadtxt(str(tmp_path / "p" / "opencv_kcf" / "alpha_s8.txt"), delimiter="\t")
    assert boxes.shape == (3, 4) and boxes[0].tolist() == [5, 6, 10, 6]
    assert os.path.isfile(str(tmp_path / "p" / "opencv_kcf" / "alpha_s8_time.txt"))


def test_export_refuses_a_folder_without_sequences(tmp_path):
    r = _cli("export", str(tmp_path), "--format", "uav123", "--out", str(tmp_path / "o"))
    assert r.returncode == 1 and "no sequences (folders with groundtruth_rect.txt) in %s" % tmp_path in r.stderr


def test_per_frame_fps_is_the_mean_of_the_frame_rates_as_got10k_averages_it():
    # frames of 0.01 s and 0.04 s: got10k's mean(1/t) = (100 + 25) / 2 = 62.5, not 2 / 0.05 = 40; t = 0 is left out
    assert X.per_frame_fps([0.01, 0.04, 0.0]) == pytest.approx(62.5)


def test_baselines_answer_the_first_box_and_the_centred_first_size():
    image = np.zeros((180, 320, 3), np.uint8)
    static, centre = T.make_tracker("baseline:static"), T.make_tracker("baseline:centre")
    for tracker in (static, centre):
        tracker.init(image, (10, 20, 30, 40))
    assert static.update(image) == (10.0, 20.0, 30.0, 40.0) == static.update(image)
    assert centre.update(image) == (145.0, 70.0, 30.0, 40.0)  # (320 - 30) / 2, (180 - 40) / 2


def test_a_tracker_missing_sequences_is_marked_and_not_ranked_with_the_complete_ones(sequences, tmp_path):
    from sim4cv import experiment_report, ope
    # 'crashy' crashed on beta_s4 (no result) but is perfect on alpha_s8; 'steady' is mediocre on both
    results = tmp_path / "results"
    for tracker, seqs, lines in (("crashy", ["alpha_s8"], TRUTH), ("steady", ["alpha_s8", "beta_s4"],
                                                                   ["4,5,10,6"] * 4)):
        (results / tracker).mkdir(parents=True)
        for seq in seqs:
            (results / tracker / (seq + ".txt")).write_text("\n".join(lines) + "\n")
    report = ope.evaluate(sequences, str(results), "otb")
    assert report["trackers"]["crashy"]["success_auc"] > report["trackers"]["steady"]["success_auc"]
    records = [{"kind": "offline", "tracker": t, "tracker_dir": t, "sequence": s, "frames": 4, "tracker_fps": 100.0,
                "fps_per_frame": 100.0, "error": "" if (t, s) != ("crashy", "beta_s4") else "RuntimeError: boom"}
               for t in ("crashy", "steady") for s in ("alpha_s8", "beta_s4")]
    exp = {"name": "t", "kind": "offline", "convention": "otb", "trackers": ["crashy", "steady"]}
    experiment_report.write_all(exp, records, str(tmp_path), "test", 1.0, report)
    table = [line for line in (tmp_path / "report.md").read_text().splitlines() if line.startswith("| ")]
    order = [line.split(" | ")[0][2:] for line in table[1:] if not line.startswith("| tracker |")]
    assert order.index("steady") < order.index("crashy (1 of 2 sequences: not ranked)")
