"""The realism probe (bench/realism_probe.py) on two frames against the real
daemon: its JSON has the documented structure, and the walkers it lists as
ground truth are exactly the mask's: each pedestrian's box and pixel count are
the tight box and count of its id in the saved mask, and the walkers to find
are those the mask shows at least 96 px tall, inside the image. No recall
threshold: the probe measures, it does not pass or fail the renderer."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PROBE = os.path.join(REPO_ROOT, "bench", "realism_probe.py")
sys.path.insert(0, os.path.join(REPO_ROOT, "bench"))

from realism_detectors import mask_box  # noqa: E402

DETECTORS = ["hog_default", "hog_daimler", "haar_fullbody", "haar_upperbody"]


def run_probe(out):
    subprocess.run([sys.executable, PROBE, "--out", str(out), "--frames", "2", "--presets", "clear_noon",
                    "--save-frames", "--photos"], check=True, timeout=240, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "realism_probe.json")) as f:
        return json.load(f)


def test_probe_lists_the_walkers_the_mask_shows(tmp_path):
    result = run_probe(tmp_path)
    assert result["detectors"] == DETECTORS  # scripts/setup.sh installs opencv-data's cascades
    assert result["car_detectors"] == []
    summary = result["summary"]["clear_noon"]
    frames = result["frames"]["clear_noon"]
    assert summary["frames"] == len(frames) == 2 and [f["traffic_walker"] for f in frames] == [False, True]
    assert summary["walkers"] == sum(p["to_find"] for f in frames for p in f["pedestrians"]) >= 2
    for index, frame in enumerate(frames):
        mask = cv2.imread(str(tmp_path / "frames" / ("clear_noon_%03d_mask.png" % index)), cv2.IMREAD_UNCHANGED)
        assert mask.dtype == np.uint16 and mask.shape == (480, 640)
        aimed = [p for p in frame["pedestrians"] if p["object_id"] == frame["walker_aimed_at"]]
        assert aimed and (aimed[0]["to_find"] or frame["traffic_walker"]), "the spawned walker faced is one to find"
        for walker in frame["pedestrians"]:
            box, pixels = mask_box(mask, walker["object_id"])
            assert list(box) == walker["box"] and pixels == walker["visible_pixels"], walker
            x, y, w, h = box
            inside = x > 0 and y > 0 and x + w < 640 and y + h < 480
            assert walker["to_find"] == (h >= 96 and inside and walker["visibility"] >= 0.5), walker
        for name in DETECTORS:
            found, fp, boxes = frame[name]["found"], frame[name]["false_positives"], frame[name]["boxes"]
            assert 0 <= found <= sum(p["to_find"] for p in frame["pedestrians"]) and fp == len(boxes) - found
    for name in DETECTORS:
        found = sum(f[name]["found"] for f in frames)
        assert summary[name]["found"] == found and summary[name]["recall"] == round(found / summary["walkers"], 4)
    table = (tmp_path / "realism_probe.md").read_text()
    assert table.startswith("| preset | frames | walkers | hog_default |") and "| clear_noon | 2 |" in table
    assert "Offline car detectors packaged with OpenCV: none" in table
