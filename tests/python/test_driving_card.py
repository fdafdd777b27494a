"""The model card (sim4cv.driving_card): the shipped model's card gives the
plain `evaluate` command the settings the model was selected with, flags
still win, the report says where each setting came from, and a card that
does not fit its model is refused."""

import argparse
import json
import os
import subprocess
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_card as dcard  # noqa: E402
from sim4cv import driving_control as dc  # noqa: E402

SHIPPED = os.path.join(REPO_ROOT, "models", "driving")
PYTHON_DIR = os.path.join(REPO_ROOT, "clients", "python")


def _args(argv):
    p = argparse.ArgumentParser()
    p.add_argument("--speed", type=float)
    p.add_argument("--frame-hz", type=float)
    dc.add_arguments(p)
    return p, p.parse_args(argv)


def test_the_shipped_card_fills_unset_settings_and_flags_win():
    card = dcard.for_model(os.path.join(SHIPPED, "model.onnx"), (90, 160, True))
    p, a = _args(["--steer-gain", "0.8"])
    sources = dcard.apply(a, card)
    controller = dc.from_arguments(p, a)
    assert (controller.steer_waypoint, controller.gain, controller.slowdown) == (2, 0.8, 0.5)
    assert (controller.bend, controller.bend_limit) == (0.2, 1.5)
    assert (a.speed, a.frame_hz) == (8.0, 30.0)
    assert sources["steer_gain"] == "--steer-gain"
    assert sources["steer_waypoint"] == "model card %s" % os.path.join(SHIPPED, "model.json")
    assert "steer_waypoint 2 (model card" in dcard.describe(a, sources)


def test_without_a_card_the_defaults_are_the_papers_rule(tmp_path):
    p, a = _args([])
    assert dcard.for_model(str(tmp_path / "model.onnx"), None) is None
    sources = dcard.apply(a, None)
    assert set(sources.values()) == {"default"}
    assert dc.from_arguments(p, a) == dc.Controller(1, 1.0, 0.0, 0.0, None)


def test_a_card_that_does_not_fit_its_model_or_is_malformed_is_refused(tmp_path):
    card = dcard.card_for(90, 160, True)
    (tmp_path / "model.json").write_text(json.dumps(card))
    model = str(tmp_path / "model.onnx")
    with pytest.raises(dcard.CardError, match=r"describes a 160x90 network with a goal input, but .*model.onnx is "
                                              r"320x180$"):
        dcard.for_model(model, (180, 320, False))
    card["controller"]["steer_gain"] = -1
    (tmp_path / "model.json").write_text(json.dumps(card))
    with pytest.raises(dcard.CardError, match='controller setting "steer_gain" has a bad value -1'):
        dcard.read(model)
    card["controller"] = {"steering_gain": 1}
    (tmp_path / "model.json").write_text(json.dumps(card))
    with pytest.raises(dcard.CardError, match='unknown controller setting "steering_gain"'):
        dcard.read(model)
    (tmp_path / "model.json").write_text("{")
    with pytest.raises(dcard.CardError, match="model.json is not readable JSON"):
        dcard.read(model)


def test_the_plain_command_drives_the_shipped_model_as_it_was_selected(tmp_path):
    # test/04 desert: with the paper's rule (waypoint 1, gain 1) the shipped
    # model leaves the road at 226 m; with its card's settings it keeps the lane.
    out = tmp_path / "eval"
    r = subprocess.run([sys.executable, "-m", "sim4cv.driving", "evaluate", "--model",
                        os.path.join(SHIPPED, "model.onnx"), "--maps",
                        os.path.join(REPO_ROOT, "scenes", "driving", "test", "04_desert.map"), "--out", str(out)],
                       cwd=PYTHON_DIR, capture_output=True, text=True, timeout=280)
    assert r.returncode == 0, r.stderr
    assert "steer_waypoint 2 (model card" in r.stdout and "steer_gain 0.9 (model card" in r.stdout
    report = json.loads((out / "driving.json").read_text())
    s = report["settings"]
    assert (s["steer_waypoint"], s["steer_gain"], s["slowdown"], s["speed_m_s"], s["frame_hz"]) == (2, 0.9, 0.5, 8.0, 30.0)
    assert (s["bend_correction"], s["bend_limit_m"]) == (0.2, 1.5)
    assert s["settings_from"]["steer_gain"].startswith("model card ")
    o = report["overall"]
    assert o["completed"] == 1 and o["lane_departures"] == 0
