"""sim4cv.driving_client against a real sim4cvd: frames over shared memory
with controls over UDP (realtime), and lockstep over TCP with a lane change
to the left lane and back."""

import math
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv import driving_client as dcl  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_metrics as dm  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402

MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")
NO_TRAFFIC = ["--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0"]


def car_deviation(address):
    """(signed deviation from the right lane's centre, metres from the start) of the map's car."""
    info = dd.parse_map(MAP)
    path = dd.RoutePath(info, next(iter(info["routes"])))
    with sim4cv.connect(address) as c:
        p = next(e.position for e in c.get_state().entities if e.name == "car")
    u = dm.nearest_u(path, p.x, p.y)
    progress = dm.Progress(path, u)
    return progress.update(p.x, p.y), p


def test_realtime_frames_over_shm_controls_over_udp():
    flags = ["--map", MAP, "--shm-name", "drivetest%d" % os.getpid(), "--shm-camera", "car_front",
             "--shm-channels", "rgb"] + NO_TRAFFIC
    with OwnDaemon(flags, mode="realtime") as d:
        start = car_deviation(d.address)[1]
        result = dcl.drive("shm://drivetest%d" % os.getpid(), "udp://127.0.0.1:%s" % d.fields["udp"],
                           dcl.ReferenceDriver(MAP), seconds=4.0, log=lambda *a: None)
        deviation, end = car_deviation(d.address)
    assert result["frames"] >= 60  # 30 Hz, minus what a loaded machine skips
    assert result["frames"] + result["skipped"] >= 100
    assert math.hypot(end.x - start.x, end.y - start.y) > 15.0
    assert abs(deviation) < 0.3


def test_lockstep_lane_change_to_the_left_and_back():
    with OwnDaemon(["--map", MAP] + NO_TRAFFIC, mode="lockstep") as d:
        lane = dcl.Lane("right")
        driver = dcl.ReferenceDriver(MAP)
        dcl.drive(d.address, None, driver, lockstep=True, frames=90, lane=lane, log=lambda *a: None)
        lane.lane = "left"  # what typing `left` on stdin does
        dcl.drive(d.address, None, driver, lockstep=True, frames=180, lane=lane, log=lambda *a: None)
        left, _ = car_deviation(d.address)
        lane.lane = "right"
        dcl.drive(d.address, None, driver, lockstep=True, frames=180, lane=lane, log=lambda *a: None)
        right, _ = car_deviation(d.address)
    assert left == pytest.approx(-4.0, abs=0.4)  # the left lane's centre
    assert abs(right) < 0.4


def test_lane_switches_on_a_timer():
    lane = dcl.Lane("right", switch_every=2.0)
    assert [lane.tick(t) for t in (0.0, 1.9, 2.0, 3.9, 4.0)] == ["right", "right", "left", "left", "right"]


def test_an_unknown_car_is_refused():
    with OwnDaemon(["--map", MAP] + NO_TRAFFIC, mode="lockstep") as d:
        with pytest.raises(Exception, match="no entity called 'bus'"):
            dcl.drive(d.address, None, dcl.ReferenceDriver(MAP), car="bus", lockstep=True, frames=1)
