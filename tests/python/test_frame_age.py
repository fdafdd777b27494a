"""Frame age on request: a realtime daemon renders at 30 Hz; a reader asks for
a frame every 100 ms (10 Hz) with request_frame() and gets a new frame each
time, never one held back from seconds ago, over each transport. The limit
is a margin that holds on a machine busy with a parallel build; how old the
frames really are (median and p90, about a frame period plus transfer) is
measured by bench/bench_frame_age.cpp (docs/benchmarks.md, "How old a slow
reader's frames are")."""

import statistics
import time

import pytest

import sim4cv

REQUESTS = 20
# A stale frame (a mailbox that kept an old one) is as old as the test has run:
# seconds. A fresh one is a frame period plus transfer, tens of ms on an idle host.
STALE_MS = 1500


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
    assert median < STALE_MS, ages
