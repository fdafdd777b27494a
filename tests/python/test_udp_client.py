"""The UDP client (docs/protocol.md section 12) against the real daemon, and
its chunk reassembly on its own."""

import time

import pytest

import sim4cv
from sim4cv import pb
from sim4cv.reassembly import FrameReassembler


def _udp(daemon, **options):
    return sim4cv.connect(daemon.address("udp"), name="pytest-udp", **options)


def test_lockstep_over_udp(start_daemon):
    daemon = start_daemon("--udp-port", "0", "--udp-datagram-bytes", "8000")  # many chunks per frame
    with _udp(daemon) as client:
        assert isinstance(client, sim4cv.UdpClient) and client.welcome.client_id >= 1
        subscribed = client.subscribe("uav", ["rgb", "depth", "boxes"], "lockstep")
        assert subscribed.camera == "uav"
        frames = list(client.frames(count=5))
        assert [f.frame_id for f in frames] == [1, 2, 3, 4, 5]
        frame = frames[-1]
        assert frame.message is not None and frame.message.frame_id == 5
        rgb, depth = frame.image("rgb"), frame.image("depth")
        assert rgb.shape == (180, 320, 3) and rgb.dtype.name == "uint8" and rgb.any()
        assert depth.shape == (180, 320) and depth.dtype.name == "float32"
        assert frame.box(1) is not None and frame.box(1).width > 0
        assert client.reassembler.completed == 5 and client.reassembler.dropped == 0
        client.send_tracker_output(frame.frame_id, 10, 20, 30, 40, 0.5)
        state = client.get_state()
        assert state.frame_id == 5 and state.entities
        counters = client.get_stats().counters
        assert counters["udp.frames_sent"] >= 5 and counters["udp.chunks_sent"] >= 5 * 20
        assert client.sequence >= 9  # Hello, Subscribe, 5 Steps, TrackerOutput, GetState, GetStats


def test_keep_alives_hold_the_registration_while_waiting(start_daemon):
    # Keep-alives every 0.2 s against a 2 s expiry: a busy machine may pause
    # this process for a while without the registration lapsing.
    daemon = start_daemon("--udp-port", "0", "--udp-expiry-ms", "2000")
    with _udp(daemon, keepalive_interval=0.2) as client:
        client.subscribe("uav", ["rgb"], "lockstep")
        assert client.step_and_receive().frame_id == 1
        with pytest.raises(TimeoutError):
            client.receive_frame(timeout=3.0)  # no Step: nothing comes, but keep-alives go out
        assert "udp.expired" not in client.get_stats().counters
        assert client.step_and_receive().frame_id == 2  # same registration, same subscription


def test_an_error_arrives_as_server_error(start_daemon):
    daemon = start_daemon("--udp-port", "0")
    with _udp(daemon) as client:
        with pytest.raises(sim4cv.ServerError) as info:
            client.subscribe("no_such_camera", ["rgb"], "lockstep")
        assert info.value.code == pb.ERROR_CODE_UNKNOWN_CAMERA and "no_such_camera" in info.value.message


def test_configure_over_udp(start_daemon):
    daemon = start_daemon("--udp-port", "0")
    with _udp(daemon) as client:
        before = len(client.get_world().entities)
        uav = client.spawn("uav", "uav_b", 0, 0, 20)
        world = client.get_world()
        assert len(world.entities) == before + 1 and any(e.id == uav for e in world.entities)
        with pytest.raises(sim4cv.ServerError) as info:
            client.remove(987654)
        assert info.value.request_id == client._request_id


def test_a_repeated_configure_request_id_is_not_carried_out_twice(start_daemon):
    # docs/protocol.md: a Configure whose request_id equals one of the last 16
    # this UDP client sent is not carried out again; its answer is sent again.
    daemon = start_daemon("--udp-port", "0")
    with _udp(daemon) as client:
        before = len(client.get_world().entities)
        request = pb.Envelope()
        request.configure.spawn.CopyFrom(pb.Spawn(kind=pb.ENTITY_KIND_UAV, name="", position=pb.Vec3(z=20)))
        request.configure.request_id = 4242
        for _ in range(3):  # as retries would: same request_id, new sequence numbers
            client._send(request)
        answers = []
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and len(answers) < 3:
            client._receive_one(0.1)
            answers += [m for k, m in list(client._replies) if k == "configured" and m.request_id == 4242]
            client._replies.clear()
        assert answers, "no answer to the Configure"
        assert len({a.entity_id for a in answers}) == 1, "one spawn, the same answer repeated"
        assert len(client.get_world().entities) == before + 1


def _chunks(frame_id, payload, size):
    count = (len(payload) + size - 1) // size
    return [pb.FrameChunk(frame_id=frame_id, chunk_index=i, chunk_count=count, frame_bytes=len(payload),
                          offset=i * size, data=payload[i * size:(i + 1) * size]) for i in range(count)]


def test_reassembly_in_any_order_and_dropping_incomplete_frames():
    r = FrameReassembler()
    # Chunks of 600 bytes: the daemon's smallest datagram (576) carries at least 533.
    one, two, three = bytes(range(250)) * 8, bytes(1000) + b"x" * 100, b"y" * 1200
    c1 = _chunks(1, one, 600)
    assert [r.add(c) for c in (c1[2], c1[0], c1[3])] == [None] * 3
    assert r.add(c1[0]) is None and r.stale == 1  # duplicate
    assert bytes(r.add(c1[1])) == one and r.completed == 1
    assert r.add(c1[1]) is None and r.stale == 2  # straggler of a finished frame
    c2, c3 = _chunks(2, two, 600), _chunks(3, three, 600)
    assert r.add(c2[0]) is None
    assert r.add(c3[1]) is None and r.dropped == 1  # frame 3 overtook the incomplete frame 2
    assert r.add(c2[1]) is None and r.stale == 3
    assert bytes(r.add(c3[0])) == three and r.completed == 2
    bad = pb.FrameChunk(frame_id=9, chunk_index=2, chunk_count=2, frame_bytes=10, offset=0, data=b"ab")
    assert r.add(bad) is None and r.invalid == 1
    restarted = _chunks(1, b"z" * 10, 64)[0]  # LoadMap/Reset: frame ids start at 1 again
    assert bytes(r.add(restarted)) == b"z" * 10
