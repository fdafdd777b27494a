"""Tracking in the loop (sim4cv.tracking) against real daemons: trackers fly
UAVs through the daemon's servo (docs/tracking.md, "Online evaluation")."""

import csv
import json
import os

import pytest

from conftest import REPO_ROOT
from sim4cv.tracking import Session, run_session

NCC = os.path.join(REPO_ROOT, "clients", "python", "examples", "trax_ncc_tracker.py")


def run(tmp_path, **fields):
    return run_session(Session(**fields), str(tmp_path))["results"]


def test_the_ground_truth_tracker_completes_the_run(tmp_path):
    (gt,) = run(tmp_path, map="tracking/easy_urban", speed=6, trackers=["gt"], seconds=8)
    assert gt["error"] == "" and not gt["lost"] and gt["completion"] == 1.0
    assert gt["frames_skipped"] == 0 and abs(gt["frames_processed"] - 240) <= 2
    assert gt["mean_center_error_px"] == 0.0
    with open(tmp_path / "frames_0.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == gt["frames_processed"]
    assert os.path.getsize(tmp_path / "run.s4log") > 0
    assert json.loads((tmp_path / "session.json").read_text())["results"][0]["tracker"] == "gt"


def test_two_uavs_in_one_world_each_with_its_tracker(tmp_path):
    results = run(tmp_path, map="tracking/easy_urban", speed=4, trackers=["gt", "gt"], seconds=6)
    assert [r["camera"] for r in results] == ["uav", "uav_1_cam"]
    assert len({r["uav"] for r in results}) == 2
    for r in results:
        assert r["error"] == "" and not r["lost"], r


def test_in_realtime_a_slow_answer_skips_frames(tmp_path):
    # 100 ms added to every answer: a 10 Hz tracker of a 30 Hz camera.
    (gt,) = run(tmp_path, map="tracking/easy_urban", speed=4, trackers=["gt"], mode="realtime", seconds=4,
                delay_ms=100)
    assert gt["error"] == ""
    assert gt["frames_processed"] < 50 and gt["frames_skipped"] > gt["frames_processed"], gt


def test_a_tracker_that_loses_the_target_ends_its_run_with_the_distance_covered(tmp_path):
    (corner,) = run(tmp_path, map="tracking/easy_urban", speed=6, trackers=["python:fixed_trackers:corner"],
                    seconds=20, lost_after_s=1.0)
    assert corner["lost"] and corner["error"] == ""
    assert corner["seconds"] < 20 and 0 < corner["completion"] < 1, corner


def test_a_failing_tracker_is_reported_and_the_others_fly_on(tmp_path):
    gt, broken = run(tmp_path, map="tracking/easy_urban", speed=4, trackers=["gt", "python:fixed_trackers:broken"],
                     seconds=5)
    assert "the filter blew up on frame 3" in broken["error"] and broken["lost"]
    assert gt["error"] == "" and not gt["lost"] and gt["completion"] == 1.0


def test_a_trax_tracker_flies_a_uav(tmp_path):
    (ncc,) = run(tmp_path, map="tracking/easy_urban", speed=4, trackers=["trax:/usr/bin/python3 " + NCC], seconds=6)
    assert ncc["error"] == "", ncc
    assert ncc["frames_processed"] > 100 and ncc["mean_center_error_px"] < 15, ncc


def test_a_walking_pedestrian_can_be_the_target(tmp_path):
    (gt,) = run(tmp_path, map="tracking/easy_urban", speed=2, target="pedestrian", trackers=["gt"], seconds=6)
    assert gt["error"] == "" and not gt["lost"] and gt["completion"] == 1.0
    assert 8 < gt["covered_m"] < 14  # 2 m/s for about 6 s


def test_sessions_survive_misbehaving_trackers(tmp_path):
    # five UAVs in one world: gt, and four trackers that each used to end or hang the session
    trackers = ["gt", "python:fixed_trackers:unstartable", "python:fixed_trackers:hanging",
                "python:fixed_trackers:banana", "python:fixed_trackers:refused"]
    gt, unstartable, hanging, banana, refused = run(tmp_path, map="tracking/easy_urban", speed=4, trackers=trackers,
                                                    seconds=3, tracker_timeout_s=2.0)
    # a tracker that fails to start is reported; the others fly on (no broken barrier)
    assert "no GPU here" in unstartable["error"] and unstartable["frames_processed"] == 0
    assert gt["error"] == "" and not gt["lost"] and gt["completion"] == 1.0 and gt["frames_processed"] > 80
    # a python: tracker whose update() hangs is killed after its timeout, and keeps what it flew
    assert "python:fixed_trackers:hanging: update() did not answer within 2 s; killed it" in hanging["error"]
    assert hanging["frames_processed"] == 2 and hanging["seconds"] > 0
    # junk answers: an error naming the tracker and what it answered
    assert "python:fixed_trackers:banana: update() answered 'banana'; expected (x, y, w, h) or None" \
        in banana["error"]
    # boxes the daemon refuses (far outside the image, inf) are counted and the run goes on
    assert refused["error"] == "" and refused["boxes_refused"] >= 10 and refused["frames_processed"] > 10
    # strict JSON: no NaN or Infinity in session.json (null instead)
    text = (tmp_path / "session.json").read_text()
    session = json.loads(text, parse_constant=lambda name: pytest.fail("session.json holds %s" % name))
    assert session["results"][3]["mean_center_error_px"] is None


def test_a_delay_in_lockstep_is_refused_with_a_message(tmp_path):
    with pytest.raises(ValueError, match="delay_ms 200 with mode lockstep: the simulation waits for every answer"):
        run(tmp_path, trackers=["gt"], mode="lockstep", delay_ms=200, seconds=1)
    assert not os.path.exists(tmp_path / "session.json")
