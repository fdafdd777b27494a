"""sim4cv.driving_compare: the table in the paper's layout, the findings
stated from the numbers, and a tiny real run (two arms, one map each)."""

import json
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_compare as dcmp  # noqa: E402
from sim4cv import driving_control as dc  # noqa: E402


def overall(mean, within25, runs=4, completed=4):
    return {"mean_deviation_cm": mean, "within_25cm": within25, "within_50cm": 1.0, "within_1m": 1.0,
            "lane_departures": 0, "completed": completed, "runs": runs}


def test_table_and_findings_from_numbers():
    results = {"none": {"overall": overall(80.0, 0.2, completed=1), "images": 100},
               "fixed": {"overall": overall(14.0, 0.9), "images": 400},
               "random": {"overall": overall(9.5, 0.95), "images": 400}}
    text = dcmp.table(results)
    assert text.splitlines()[0] == ("| | none views (here) | fixed views (here) | random views (here) | "
                                    "random views (paper) | fixed views (paper) |")
    assert "| % in [-25 cm, 25 cm] | 0.2000 | 0.9000 | 0.9500 | 0.9550 | 0.8944 |" in text
    assert "| Avg deviation [cm] | 80.00 | 14.00 | 9.50 | 7.12 | 14.61 |" in text
    f = dcmp.findings(results)
    assert f[0].startswith("without augmentation: 3 of 4 laps left the road") and f[0].endswith("holds in part")
    assert "random views 9.50 cm vs fixed views 14.00 cm" in f[1] and f[1].endswith("-> holds")


def test_fixed_views_get_the_random_arms_image_budget():
    assert dcmp.views_per_pose("none", 3) == 1
    assert dcmp.views_per_pose("random", 3) == 4
    assert dcmp.views_per_pose("fixed", 3) == 25


def test_a_tiny_comparison_runs_end_to_end(tmp_path):
    pytest.importorskip("torch")
    m = os.path.join(REPO_ROOT, "scenes", "driving", "val", "01_desert.map")
    t = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_desert.map")
    result = dcmp.run(str(tmp_path), [m], [m], [t], step=8.0, random_views=1, epochs=1, max_minutes=1,
                      surroundings=["desert"], arms=["none", "random"], max_samples=4,
                      controller=dc.Controller(steer_waypoint=2),
                      log=lambda *a: None)
    assert set(result["arms"]) == {"none", "random"}
    assert result["arms"]["none"]["images"] == 4 and result["arms"]["random"]["images"] == 8
    with open(tmp_path / "comparison.json") as f:
        assert json.load(f)["arms"]["random"]["overall"]["runs"] == 1
    assert (tmp_path / "comparison.md").read_text().startswith("| | none views (here) | random views (here) |")
    assert (tmp_path / "random" / "eval" / "histogram.png").is_file()
    # every arm's network takes the goal, from relabelled datasets (the way at each junction)
    with open(tmp_path / "none" / "model" / "training.json") as f:
        assert json.load(f)["settings"]["goal"] is True
    for folder in ("val", "none/dataset", "random/dataset"):
        assert (tmp_path / folder / "labels.csv").read_text().splitlines()[0].endswith(",junction,obstacle")
    with open(tmp_path / "random" / "eval" / "driving.json") as f:
        assert json.load(f)["settings"]["steer_waypoint"] == 2  # every arm is driven with the same controller
