"""The shared-memory client (docs/protocol.md section 13) against the real daemon."""

import struct
import threading
import time

import numpy as np
import pytest

import sim4cv
from conftest import Daemon, unique_shm_name
from sim4cv import pb, shm_layout


def _shm(daemon, **options):
    return sim4cv.connect(daemon.address("shm"), name="pytest-shm", **options)


def test_lockstep_over_shm_zero_copy_views(start_transports_daemon):
    daemon = start_transports_daemon()
    with _shm(daemon) as client:
        assert isinstance(client, sim4cv.ShmClient) and client.ring_geometry.camera_name == "uav"
        client.subscribe("uav", ["rgb", "depth", "mask", "boxes"], "lockstep")
        frames = []
        for frame in client.frames(count=4):
            frames.append(frame.frame_id)
            assert isinstance(frame, sim4cv.ShmFrame) and frame.message is None
        assert frames == [1, 2, 3, 4]
        rgb, depth, mask = frame.image("rgb"), frame.image("depth"), frame.image("mask")
        assert rgb.shape == (180, 320, 3) and rgb.dtype == np.uint8 and not rgb.flags.writeable and rgb.any()
        assert depth.shape == (180, 320) and depth.dtype == np.float32 and np.isfinite(depth).any()
        assert mask.shape == (180, 320) and mask.dtype == np.uint16
        car = frame.box(1)
        assert car is not None and car.width > 0 and (mask == 1).sum() == car.visible_pixels
        assert {e.id for e in frame.entities} >= {1, 2}
        copied = frame.copy()
        frame.check()
        assert np.array_equal(copied.image("rgb"), rgb) and copied.image("rgb").flags.writeable
        assert client.get_state().frame_id == 4
        client.send_tracker_output(frame.frame_id, 1, 2, 3, 4, 0.9)
        assert client.get_stats().counters is not None


def test_shm_frame_equals_the_same_frame_over_tcp(start_transports_daemon):
    daemon = start_transports_daemon("--shm-channels", "rgb")
    tcp = sim4cv.connect(daemon.address("tcp"), name="tcp-twin")
    with tcp, _shm(daemon) as shm:
        tcp.subscribe("uav", ["rgb"], "lockstep")
        shm.subscribe("uav", ["rgb"], "lockstep")
        # Both step (the simulation advances when every lockstep client has), past the ring's
        # last slot, so every slot's views (made once per slot) are read again for a newer frame.
        for _ in range(shm.ring_geometry.slot_count + 2):
            shm.step()
            over_tcp = tcp.step_and_receive()
            over_shm = shm.receive_frame()
            assert over_shm.frame_id == over_tcp.frame_id
            assert np.array_equal(over_shm.image("rgb"), over_tcp.image("rgb"))
            assert over_shm.render_end_mono_ns == over_tcp.render_end_mono_ns
        with pytest.raises(KeyError, match="CHANNEL_DEPTH"):
            over_shm.image("depth")
        with pytest.raises(sim4cv.ServerError) as info:
            shm.subscribe("uav", ["rgb", "depth"], "lockstep")
        assert "--shm-channels" in info.value.message


def test_a_view_goes_stale_once_the_slot_is_overwritten(start_transports_daemon):
    daemon = start_transports_daemon("--shm-slots", "2", "--shm-channels", "rgb")
    with _shm(daemon) as client:
        client.subscribe("uav", ["rgb"], "lockstep")
        first = client.step_and_receive()
        view, kept = first.image("rgb"), first.copy()
        client.step_and_receive()  # the other slot
        first.check()
        client.step_and_receive()  # first's slot again
        assert first.stale
        with pytest.raises(sim4cv.StaleFrameError, match="overwritten"):
            first.check()
        with pytest.raises(sim4cv.StaleFrameError):
            first.image("rgb")
        with pytest.raises(sim4cv.StaleFrameError):
            first.copy()
        assert kept.frame_id == 1 and kept.image("rgb").shape == view.shape


def test_another_layout_version_is_refused_naming_both(start_transports_daemon):
    daemon = start_transports_daemon()
    with _shm(daemon) as client:
        header = bytearray(client._ring.frames[:4096])
    geometry = shm_layout.parse_ring_header(header, len(header) + 10 ** 9)
    assert geometry.slot_count == 8 and geometry.channel_mask == 0x0e
    struct.pack_into("<I", header, 8, 7)
    with pytest.raises(sim4cv.ShmLayoutError) as info:
        shm_layout.parse_ring_header(header, 10 ** 9)
    assert isinstance(info.value, sim4cv.Sim4cvError)
    assert "layout version 7" in str(info.value) and "layout version 4" in str(info.value)
    header[0:8] = b"NOTSIM4C"
    with pytest.raises(sim4cv.ShmLayoutError, match="SIM4CVSM"):
        shm_layout.parse_ring_header(header, 10 ** 9)


def test_configure_goes_over_a_companion_tcp_connection(start_transports_daemon):
    daemon = start_transports_daemon()
    with _shm(daemon) as client:
        uav = client.spawn("uav", "uav_b", 5, 5, 20)
        assert any(e.id == uav for e in client.get_world().entities)
        assert client._tcp is not None


def test_long_welcomes_and_states_arrive_whole_at_every_attachment(start_transports_daemon):
    # 60 entities with 63-byte names: a Welcome and a State of several KB,
    # longer than a response message, come over the attachment's socket.
    daemon = start_transports_daemon()
    names = {("uav-with-a-long-name-%03d-" % i).ljust(63, "x") for i in range(60)}
    with sim4cv.connect(daemon.address("tcp"), name="spawner") as tcp:
        for i, name in enumerate(sorted(names)):
            tcp.spawn("uav", name, -100 + 6 * (i % 30), 60 + 6 * (i // 30), 25)
        tcp.subscribe("uav", ["boxes"], "lockstep")
        tcp.step_and_receive()  # the published State lists them too
        assert tcp.welcome.ByteSize() < 2 * shm_layout.RESPONSE_DATA_BYTES  # its Welcome came before them
    for attempt in range(3):
        with _shm(daemon) as client:
            assert client.welcome.ByteSize() > 2 * shm_layout.RESPONSE_DATA_BYTES
            assert names <= {e.name for e in client.welcome.entities}, "attachment %d" % attempt
            state = client.get_state()
            assert names <= {e.name for e in state.entities}
            assert client.responses_lost == 0


def test_idle_client_is_kept_attached_while_waiting_and_reattaches_after_expiry(start_transports_daemon):
    # Keep-alives every 0.15 s against a 1.5 s expiry: a busy machine may
    # pause this process for a while without the attachment lapsing.
    daemon = start_transports_daemon("--shm-expiry-ms", "1500")
    with _shm(daemon, keepalive_interval=0.15) as client:
        client.subscribe("uav", ["rgb"], "lockstep")
        with pytest.raises(TimeoutError):
            client.receive_frame(timeout=2.5)  # no Step: waits, sending keep-alives
        assert client.step_and_receive().frame_id == 1
        time.sleep(3.0)  # silent, not waiting: the daemon ends the attachment
        with pytest.raises((sim4cv.ConnectionClosed, sim4cv.ServerError)) as info:
            client.get_state()
        assert "expiry" in str(info.value) or "attach" in str(info.value)
        client.hello()  # attaches anew
        client.subscribe("uav", ["rgb"], "lockstep")
        assert client.step_and_receive().frame_id == 2


def test_daemon_stopping_mid_wait_raises_instead_of_hanging(start_transports_daemon):
    daemon = start_transports_daemon()
    client = _shm(daemon)
    client.subscribe("uav", ["rgb"], "lockstep")
    threading.Timer(0.3, daemon.proc.terminate).start()
    start = time.monotonic()
    with pytest.raises(sim4cv.ConnectionClosed, match="stopped|ended"):
        client.receive_frame(timeout=120)
    assert time.monotonic() - start < 60  # the daemon's end was noticed, not the 120 s timeout (margin for busy hosts)
    client.close()


def test_daemon_killed_mid_wait_raises_instead_of_hanging(tmp_path):
    daemon = Daemon(["--shm-name", unique_shm_name()], tmp_path)
    try:
        client = _shm(daemon)
        client.subscribe("uav", ["rgb"], "lockstep")
        threading.Timer(0.3, daemon.kill).start()
        start = time.monotonic()
        with pytest.raises(sim4cv.ConnectionClosed):
            client.receive_frame(timeout=120)
        assert time.monotonic() - start < 60  # the death was noticed, not the 120 s timeout
        client.close()
    finally:
        daemon.kill()
        daemon.terminate()
