"""sim4cv.pilot: the piloted camera respects its limits, is driven by its
seed alone, and a generated sequence replays byte for byte (real daemons)."""

import json
import math
import os

import numpy as np

from sim4cv import pilot as P
from sim4cv import sequences as S

FRAMES = 40


def _fly(seed, steps=1500, hz=30.0):
    pilot = P.Pilot(seed, hz)
    poses = [pilot.start((0.0, 0.0, 0.75), 0.0)]
    kinds = set()
    for i in range(1, steps):
        t = i / hz  # the car drives a circle of 40 m at 8 m/s
        angle = 8.0 * t / 40.0
        poses.append(pilot.step((40 * math.sin(angle), 40 - 40 * math.cos(angle), 0.75), angle))
        kinds.add(pilot.manoeuvre["kind"])
    return np.array(poses), kinds


def test_the_pilot_turns_and_tilts_no_faster_than_its_limits_and_flies_its_manoeuvres():
    poses, kinds = _fly(3, steps=3000)
    s, dt = P.PilotSettings(), 1 / 30.0
    yaw_steps = np.abs((np.diff(poses[:, 3]) + 180) % 360 - 180)
    assert yaw_steps.max() <= s.max_yaw_rate * dt + 1e-9
    assert np.abs(np.diff(poses[:, 4])).max() <= s.max_pitch_rate * dt + 1e-9
    assert 5 - 1e-9 <= poses[:, 4].min() and poses[:, 4].max() <= 89 + 1e-9
    # it does fly: orbits, fly-bys and altitude changes move the camera well away from one station
    assert np.ptp(poses[:, 2]) > 3 and {"orbit", "flyby", "climb", "reframe", "follow"} <= kinds


def test_the_same_seed_flies_the_same_path_and_another_seed_another():
    a, _ = _fly(7, steps=300)
    b, _ = _fly(7, steps=300)
    c, _ = _fly(8, steps=300)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)


def _fly_losing_the_car(seed, hidden_from, hidden_frames, steps, hz=30.0):
    """The car drives straight east at 8 m/s; from frame hidden_from on it is wholly hidden for hidden_frames."""
    pilot = P.Pilot(seed, hz)
    pilot.start((0.0, 0.0, 0.75), 0.0)
    rows, poses = [], []
    for i in range(1, steps):
        hidden = hidden_from <= i < hidden_from + hidden_frames
        poses.append(pilot.step((8.0 * i / hz, 0.0, 0.75), 0.0, 0.0 if hidden else 1.0))
        rows.append(pilot.record())
    return rows, np.array(poses), pilot


def test_the_pilot_climbs_and_recentres_after_losing_the_car_but_only_after_his_reaction_time():
    # the first 1.5 s are a plain centred follow: no manoeuvre of his own interferes
    rows, poses, pilot = _fly_losing_the_car(5, 10, 30, 45)
    regain = [r[-1] for r in rows]
    assert P.PILOT_HEADER[-1] == "regain" and regain[:9] == [0] * 9
    first = regain.index(1) + 1  # the step (frame) at which he reacts
    # he sees the loss after his lag, and waits regain_after_s more before acting
    assert first >= 10 + pilot.lag_frames + int(pilot.settings.regain_after_s * 30)
    assert rows[first - 1][1] == 0 and rows[first - 1][2] == 0  # the framing offsets gone: the car centred
    assert pilot.manoeuvre["altitude"] == 15.0 + pilot.settings.regain_climb  # he climbs, within his limits
    assert np.diff(poses[first - 1:, 2]).max() <= pilot.settings.max_climb / 30 + 1e-9
    # a car that was never lost, same seed: no regain, the same path up to the loss
    rows_seen, poses_seen, _ = _fly_losing_the_car(5, 10, 0, 45)
    assert all(r[-1] == 0 for r in rows_seen) and np.array_equal(poses_seen[:first - 1], poses[:first - 1])
    # a loss shorter than his reaction (a car passing under a crown for 3 frames) changes nothing he does
    _, poses_blink, _ = _fly_losing_the_car(5, 10, 3, 45)
    assert np.array_equal(poses_blink, poses_seen)


def _files(root):
    out = {}
    for folder, _, names in os.walk(root):
        for name in names:
            path = os.path.join(folder, name)
            with open(path, "rb") as f:
                out[os.path.relpath(path, root)] = f.read()
    return out


def test_a_piloted_sequence_replays_byte_for_byte(tmp_path):
    spec = S.Spec("hard_urban", 8, frames=FRAMES)
    metas = [S.generate_sequence(spec, str(tmp_path / run), log=lambda text: None) for run in ("a", "b")]
    a, b = (_files(str(tmp_path / run / spec.name)) for run in ("a", "b"))
    assert sorted(a) == sorted(b) and "pilot.csv" in a and "img/%06d.jpg" % FRAMES in a
    timing = ("generation_seconds", "images_per_second")
    for name in a:
        if name == "sequence.json":
            ja, jb = (json.loads(x[name]) for x in (a, b))
            assert {k: v for k, v in ja.items() if k not in timing} == {k: v for k, v in jb.items() if k not in timing}
        else:
            assert a[name] == b[name], name
    meta = metas[0]
    assert meta["camera_motion"] == "pilot" and meta["camera"] == "pilot" and meta["pilot"]["model"] == "sim4cv.pilot 2"
    assert meta["pilot"]["seed"] != spec.seed  # derived from (seed, name): every sequence of a set flies differently
    # the camera moved and the recorded camera poses are the flown ones
    poses = np.genfromtxt(str(tmp_path / "a" / spec.name / "poses.csv"), delimiter=",", names=True)
    assert np.ptp(poses["cam_x"]) + np.ptp(poses["cam_y"]) > 1.0
