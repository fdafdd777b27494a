"""sim4cv.driving_human: keys to smooth Controls (hand-computed), and a
scripted "person" driving a real lockstep daemon through the same client
loop, scored into driving.json like the network."""

import json
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_client as dcl  # noqa: E402
from sim4cv import driving_human as dh  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402

MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_desert.map")
LEFT, RIGHT, UP, SPACE, Q = 81, 83, 82, 32, ord("q")


def test_keys_ramp_the_steering_and_release_it():
    k = dh.KeyboardDriver()
    assert k.step(0.0) == (0.0, 0.0, 0.0)
    k.press(RIGHT, 0.0)
    k.press(UP, 0.0)
    s, t, b = k.step(0.2)       # 0.2 s at 2.5 per second
    assert s == pytest.approx(0.5) and t == 1.0 and b == 0.0
    k.press(RIGHT, 0.2)
    assert k.step(0.4)[0] == pytest.approx(1.0)  # full lock, clamped at the target
    s, t, b = k.step(0.6)       # no repeat since 0.2 s + KEY_HOLD_S: released, back at 4 per second
    assert s == pytest.approx(0.2) and t == 0.0
    k.press(SPACE, 0.6)
    assert k.step(0.7) == (0.0, 0.0, 1.0)
    k.press(ord("a"), 0.7)      # WASD too
    assert k.step(0.8)[0] == pytest.approx(-0.25)
    assert not k.done
    k.press(Q, 0.8)
    assert k.done


class ScriptedPerson(dh.KeyboardDriver):
    """Holds the accelerator below 6 m/s and taps an arrow towards the lane centre."""

    def __init__(self, scorer):
        super().__init__()
        self.scorer = scorer

    def controls(self, frame, pose, speed):
        t = frame.sim_time
        if speed < 6.0:
            self.press(UP, t)
        d = self.scorer.deviations[-1] if self.scorer.deviations else 0.0
        if abs(d) > 0.3:
            self.press(LEFT if d > 0 else RIGHT, t)
        return self.step(t)


def test_a_scripted_person_is_scored_like_the_network(tmp_path):
    scorer = dh.Scorer(MAP)
    person = ScriptedPerson(scorer)
    scorer.driver = person
    with OwnDaemon(["--map", MAP, "--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0"],
                   mode="lockstep") as d:
        dcl.drive(d.address, None, person, lockstep=True, frames=300, recorder=scorer, log=lambda *a: None)
    report = scorer.report(str(tmp_path), "script")
    with open(tmp_path / "driving.json") as f:
        stored = json.load(f)
    o = stored["overall"]
    assert stored["settings"] == {"policy": "human", "driver": "script", "maps": ["driving_test_01_desert"]}
    assert o == report["overall"] and o["samples"] == 300 and o["runs"] == 1
    assert 20.0 < o["distance_m"] < 80.0   # 10 s at up to 6 m/s
    assert o["mean_deviation_cm"] is not None and o["within_1m"] > 0.5
    assert (tmp_path / "runs" / "driving_test_01_desert_loop.csv").is_file()
    assert "lane" in person.status and "lap" in person.status
