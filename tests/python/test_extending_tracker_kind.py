"""A tracker kind added as one file (the colour kind in extending/) plus one
registration line is checked by experiment files and runs through the
offline evaluation's code path."""

import os
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT
from sim4cv import experiment, experiment_offline, ope, trackers

sys.path.insert(0, os.path.join(REPO_ROOT, "tests", "python", "extending"))


@pytest.fixture
def colour_kind():
    trackers.register_tracker_kind("colour", "colour_tracker_kind")
    yield
    del trackers.TRACKER_KINDS["colour"]


def write_sequence(folder, steps=5):
    """A red 8x8 square moving 4 px right per frame on grey, as UAV123 lays a sequence out."""
    import cv2
    os.makedirs(os.path.join(folder, "img"))
    truth = []
    for i in range(steps):
        image = np.full((48, 64, 3), 90, np.uint8)
        x, y = 10 + 4 * i, 20
        image[y:y + 8, x:x + 8] = (220, 30, 30)
        cv2.imwrite(os.path.join(folder, "img", "%06d.jpg" % (i + 1)), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        truth.append("%d,%d,8,8" % (x, y))
    with open(os.path.join(folder, "groundtruth_rect.txt"), "w") as f:
        f.write("\n".join(truth) + "\n")


def test_a_registered_kind_is_checked_and_made_like_the_built_in_ones(colour_kind):
    assert experiment.check_tracker_spec("colour:60") == "colour:60"
    assert "colour:TOLERANCE" in trackers.tracker_forms()
    with pytest.raises(experiment.ExperimentError, match="TOLERANCE is a colour distance from 1 to 255"):
        experiment.check_tracker_spec("colour:300")
    with pytest.raises(ValueError, match=r"'colour:red' is none of: gt, .*colour:TOLERANCE"):
        trackers.make_tracker("colour:red")
    assert trackers.make_tracker("colour:60").name == "colour:60"


def test_without_its_registration_line_the_kind_is_unknown():
    with pytest.raises(experiment.ExperimentError, match=r"unknown tracker specification 'colour:60' \(forms: gt, "):
        experiment.check_tracker_spec("colour:60")


def test_the_kind_tracks_a_sequence_through_the_offline_evaluation(colour_kind, tmp_path):
    write_sequence(str(tmp_path / "square"))
    result = str(tmp_path / "results" / "square.txt")
    frames, _, error = experiment_offline.track_sequence("colour:60", str(tmp_path / "square"), result)
    assert (frames, error) == (5, "")
    boxes = ope.read_boxes(result)
    truth = ope.read_boxes(str(tmp_path / "square" / "groundtruth_rect.txt"))
    assert np.abs(boxes - truth).max() <= 1.0, boxes
