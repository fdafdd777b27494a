"""Frame age on request: a realtime daemon renders at 30 Hz; a reader asks for
a frame every 100 ms (10 Hz) with request_frame() and gets frames at most a
frame period (33 ms) plus transfer old, over each transport."""

import statistics
import time

import pytest

import sim4cv

REQUESTS = 20
MEDIAN_LIMIT_MS = 33 + 15
P90_LIMIT_MS = 80


@pytest.fixture(scope="module")
def realtime_daemon(tmp_path_factory):
    from conftest import Daemon, unique_shm_name
    daemon = Daemon(["--mode", "realtime", "--frame-hz", "30", "--udp-port", "0", "--shm-name", unique_shm_name(),
                     "--shm-channels", "rgb"], tmp_path_factory.mktemp("realtime"))
    yield daemon
    assert daemon.terminate() == 0, daemon.log()


@pytest.mark.parametrize("transport", ["tcp", "udp", "shm"])
def test_frames_on_request_are_fresh(realtime_daemon, transport):
    with sim4cv.connect(realtime_daemon.address(transport), name="age-" + transport) as client:
        client.subscribe("uav", ["rgb"], "newest" if transport == "shm" else "on_request")
        client.request_frame()  # warm up
        ages, ids = [], []
        next_request = time.monotonic()
        for _ in range(REQUESTS):
            next_request += 0.1
            time.sleep(max(0.0, next_request - time.monotonic()))
            frame = client.request_frame(timeout=2.0)
            ages.append((time.monotonic_ns() - frame.render_end_mono_ns) / 1e6)
            ids.append(frame.frame_id)
            assert frame.image("rgb").shape == (180, 320, 3)
    ages.sort()
    median, p90 = statistics.median(ages), ages[int(0.9 * (len(ages) - 1))]
    print("\nframe age over %s at 10 Hz requests of a 30 Hz stream: median %.1f ms, p90 %.1f ms, max %.1f ms"
          % (transport, median, p90, ages[-1]))
    assert ids == sorted(ids) and len(set(ids)) == len(ids)
    assert median < MEDIAN_LIMIT_MS and p90 < P90_LIMIT_MS, ages
