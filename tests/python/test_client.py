"""Integration tests: the Python client against the real sim4cvd binary.

The daemon fixtures (conftest.py) start it once per test; each test ends by
sending SIGTERM and asserting exit status 0.
"""

import math
import os
import socket
import struct
import sys
import time

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv import ServerError, pb  # noqa: E402
from sim4cv.access import access_token  # noqa: E402

FRAME_TIMEOUT_S = 20.0

CAR_ID = 1
UAV_ID = 2


def raw_client(d):
    """A connected Client without a handshake."""
    client = sim4cv.Client()
    client.connect_raw("127.0.0.1", d.port)
    return client


def expect_error(client, code, fatal, timeout=FRAME_TIMEOUT_S):
    """Reads envelopes (skipping none) and asserts the next one is this Error."""
    envelope = client.receive_envelope(timeout)
    assert envelope.WhichOneof("kind") == "error", "expected an Error, got %s" % envelope
    assert envelope.error.code == code, "expected %s, got %s: %s" % (
        pb.ErrorCode.Name(code), pb.ErrorCode.Name(envelope.error.code), envelope.error.message)
    assert envelope.error.fatal == fatal, envelope.error
    assert envelope.error.message, "Error.message is empty"
    return envelope.error


def expect_closed(client):
    with pytest.raises(sim4cv.ConnectionClosed):
        client.receive_envelope(FRAME_TIMEOUT_S)


def expect_state_next(client):
    """Sends GetState and asserts the very next envelope is the State (i.e. no
    Error was queued for what was sent before)."""
    envelope = pb.Envelope()
    envelope.get_state.SetInParent()
    client.send_envelope(envelope)
    reply = client.receive_envelope(FRAME_TIMEOUT_S)
    assert reply.WhichOneof("kind") == "state", "expected State, got %s" % reply
    return reply.state


ALL_CHANNELS = [pb.CHANNEL_RGB, pb.CHANNEL_DEPTH, pb.CHANNEL_MASK, pb.CHANNEL_BOXES]
PIXEL_CHANNELS = [(pb.CHANNEL_RGB, pb.PIXEL_FORMAT_RGB8, 3),
                  (pb.CHANNEL_DEPTH, pb.PIXEL_FORMAT_DEPTH_F32, 4),
                  (pb.CHANNEL_MASK, pb.PIXEL_FORMAT_INSTANCE_U16, 2)]


def camera(welcome, name="uav"):
    matches = [c for c in welcome.cameras if c.name == name]
    assert len(matches) == 1, "Welcome.cameras: %s" % welcome.cameras
    return matches[0]


# ---------------------------------------------------------------- handshake

def test_handshake_welcome(daemon, connect):
    welcome = connect("handshake").welcome
    assert welcome.protocol_version == 1
    assert welcome.server_version
    assert welcome.scene_name == "default"
    cam = camera(welcome)
    assert (cam.width, cam.height) == (320, 180)
    assert cam.fov_y_deg == pytest.approx(60.0)
    assert cam.mounted_on == "uav"
    entities = {(e.id, e.name, e.kind) for e in welcome.entities}
    assert (CAR_ID, "car", pb.ENTITY_KIND_CAR) in entities
    assert (UAV_ID, "uav", pb.ENTITY_KIND_UAV) in entities
    assert [(t.kind, t.address) for t in welcome.transports if t.kind == pb.TRANSPORT_KIND_TCP] == [
        (pb.TRANSPORT_KIND_TCP, str(daemon.port))]
    assert welcome.mode == pb.SIM_MODE_LOCKSTEP
    assert welcome.physics_hz == pytest.approx(240.0)
    assert welcome.frame_hz == pytest.approx(30.0)


def test_version_mismatch_is_fatal(daemon):
    client = raw_client(daemon)
    envelope = pb.Envelope()
    envelope.hello.protocol_version = 2
    envelope.hello.client_name = "from-the-future"
    client.send_envelope(envelope)
    error = expect_error(client, pb.ERROR_CODE_VERSION_MISMATCH, fatal=True)
    assert "1" in error.message and "2" in error.message, error.message
    expect_closed(client)

    # The high-level API raises ServerError.
    with pytest.raises(ServerError) as info:
        sim4cv.Client().connect("127.0.0.1", daemon.port, "from-the-future", protocol_version=2)
    assert info.value.code == pb.ERROR_CODE_VERSION_MISMATCH
    assert info.value.fatal


# ---------------------------------------------------------------- frames

def check_frame_images(frame, width, height):
    assert (frame.width, frame.height) == (width, height)
    assert [img.channel for img in frame.images] == [c for c, _, _ in PIXEL_CHANNELS], \
        "images must follow the subscription's pixel channels in order"
    for img, (_, fmt, bpp) in zip(frame.images, PIXEL_CHANNELS):
        assert img.format == fmt
        assert img.stride == width * bpp
        assert len(img.data) == height * img.stride

    rgb = sim4cv.image_array(frame, pb.CHANNEL_RGB)
    depth = sim4cv.image_array(frame, pb.CHANNEL_DEPTH)
    mask = sim4cv.image_array(frame, pb.CHANNEL_MASK)
    assert rgb.shape == (height, width, 3) and rgb.dtype == np.uint8
    assert depth.shape == (height, width) and depth.dtype == np.float32
    assert mask.shape == (height, width) and mask.dtype == np.uint16
    assert rgb.min() != rgb.max(), "RGB image is uniform"

    assert not np.isnan(depth).any(), "depth has NaN"
    finite = np.isfinite(depth)
    assert finite.any(), "depth is nowhere finite"
    assert (depth[finite] > 0).all(), "finite depth must be positive"
    assert (depth[~finite] > 0).all(), "non-finite depth must be +inf"
    return mask


def check_boxes(frame, mask):
    ids = [b.object_id for b in frame.boxes]
    assert ids == sorted(ids) and len(set(ids)) == len(ids), "boxes not ordered by object_id: %s" % ids
    labelled = set(int(v) for v in np.unique(mask)) - {0}
    assert labelled == set(ids), "mask ids %s differ from box ids %s" % (sorted(labelled), ids)
    for box in frame.boxes:
        if box.object_id == CAR_ID:
            assert box.object_class == pb.OBJECT_CLASS_CAR
        elif box.object_id >= 100:
            assert box.object_class == pb.OBJECT_CLASS_BUILDING
        assert box.width > 0 and box.height > 0
        assert box.x + box.width <= frame.width and box.y + box.height <= frame.height
        assert 0 < box.visibility <= 1
        rows, cols = np.nonzero(mask == box.object_id)
        assert len(rows) == box.visible_pixels, "object %d" % box.object_id
        # Every labelled pixel lies inside the box, and the box is tight.
        assert (cols.min(), rows.min()) == (box.x, box.y), "object %d" % box.object_id
        assert (cols.max() + 1, rows.max() + 1) == (box.x + box.width, box.y + box.height), \
            "object %d" % box.object_id


def test_lockstep_frames(daemon, connect):
    client = connect("lockstep")
    cam = camera(client.welcome)
    subscribed = client.subscribe("uav", ALL_CHANNELS, pb.DELIVERY_LOCKSTEP)
    assert subscribed.camera == "uav"
    assert list(subscribed.channels) == ALL_CHANNELS
    assert subscribed.delivery == pb.DELIVERY_LOCKSTEP

    frame_period = 1.0 / client.welcome.frame_hz
    previous = None
    for _ in range(10):
        frame = client.step_and_receive(FRAME_TIMEOUT_S)
        now_ns = time.monotonic_ns()
        if previous is None:
            assert frame.frame_id == 1
        else:
            assert frame.frame_id == previous.frame_id + 1
            assert frame.sim_time == pytest.approx(previous.sim_time + frame_period, abs=1e-6)
        assert frame.camera == "uav"
        assert frame.dropped_frames == 0
        assert 0 < frame.render_end_mono_ns <= now_ns
        assert not frame.HasField("state")

        mask = check_frame_images(frame, cam.width, cam.height)
        check_boxes(frame, mask)
        car = [b for b in frame.boxes if b.object_id == CAR_ID]
        assert car, "frame %d: the car (object 1) has no box" % frame.frame_id
        assert car[0].object_class == pb.OBJECT_CLASS_CAR
        previous = frame

    # Lockstep: without a Step no frame comes.
    with pytest.raises(TimeoutError):
        client.receive_frame(timeout=0.5)


def test_custom_size(start_daemon):
    d = start_daemon("--width", "64", "--height", "48")
    client = sim4cv.Client()
    start_daemon.clients.append(client)
    welcome = client.connect("127.0.0.1", d.port, "small")
    assert (camera(welcome).width, camera(welcome).height) == (64, 48)
    client.subscribe("uav", ["rgb", "depth", "mask", "boxes"], "lockstep")
    frame = client.step_and_receive(FRAME_TIMEOUT_S)
    check_boxes(frame, check_frame_images(frame, 64, 48))


def test_with_state(daemon, connect):
    client = connect("with-state")
    client.subscribe("uav", ["boxes"], "lockstep", with_state=True)
    for expected in (1, 2, 3):
        frame = client.step_and_receive(FRAME_TIMEOUT_S)
        assert frame.frame_id == expected
        assert len(frame.images) == 0, "BOXES alone carries no pixels"
        assert frame.state.frame_id == frame.frame_id
        assert frame.state.sim_time == pytest.approx(frame.sim_time)
        assert [e.id for e in frame.state.entities] == [CAR_ID, UAV_ID]


# ---------------------------------------------------------------- errors

def test_unknown_camera_is_not_fatal(daemon, connect):
    client = connect("unknown-camera")
    with pytest.raises(ServerError) as info:
        client.subscribe("no-such-camera", ["rgb"], "lockstep")
    assert info.value.code == pb.ERROR_CODE_UNKNOWN_CAMERA
    assert not info.value.fatal
    assert "uav" in info.value.message, "the message should list the cameras"
    assert client.connected

    client.subscribe("uav", ["rgb"], "lockstep")
    frame = client.step_and_receive(FRAME_TIMEOUT_S)
    assert frame.frame_id == 1
    assert sim4cv.image_array(frame, "rgb").shape == (180, 320, 3)


def test_invalid_requests_are_not_fatal(daemon, connect):
    client = connect("invalid")

    def send(fill):
        envelope = pb.Envelope()
        fill(envelope)
        client.send_envelope(envelope)

    # Step without a lockstep subscription.
    send(lambda e: e.step.SetInParent())
    expect_error(client, pb.ERROR_CODE_INVALID_STATE, fatal=False)
    # A second Hello.
    send(lambda e: e.hello.MergeFrom(pb.Hello(protocol_version=1, client_name="again")))
    expect_error(client, pb.ERROR_CODE_INVALID_STATE, fatal=False)

    # Bad subscriptions.
    for sub in (pb.Subscribe(camera="uav", delivery=pb.DELIVERY_LOCKSTEP),
                pb.Subscribe(camera="uav", channels=[pb.CHANNEL_UNSPECIFIED], delivery=pb.DELIVERY_LOCKSTEP),
                pb.Subscribe(camera="uav", channels=[pb.CHANNEL_RGB, pb.CHANNEL_RGB],
                             delivery=pb.DELIVERY_LOCKSTEP),
                pb.Subscribe(camera="uav", channels=[pb.CHANNEL_RGB])):
        send(lambda e: e.subscribe.MergeFrom(sub))
        expect_error(client, pb.ERROR_CODE_INVALID_ARGUMENT, fatal=False)

    # Controls.
    send(lambda e: e.controls.MergeFrom(pb.Controls(entity_id=UAV_ID)))
    expect_error(client, pb.ERROR_CODE_UNKNOWN_ENTITY, fatal=False)
    send(lambda e: e.controls.MergeFrom(pb.Controls(entity_id=999)))
    expect_error(client, pb.ERROR_CODE_UNKNOWN_ENTITY, fatal=False)
    for field, value in (("steering", 1.5), ("steering", math.nan), ("throttle", -0.1),
                         ("throttle", math.inf), ("brake", 2.0)):
        send(lambda e: e.controls.MergeFrom(pb.Controls(entity_id=CAR_ID, **{field: value})))
        error = expect_error(client, pb.ERROR_CODE_INVALID_ARGUMENT, fatal=False)
        assert field in error.message, error.message

    # Tracker outputs.
    good_box = dict(x=1, y=2, width=3, height=4)
    for box, confidence in ((dict(good_box, width=0), 0.5), (dict(good_box, height=-1), 0.5),
                            (dict(good_box, x=math.nan), 0.5), (good_box, 1.5), (good_box, math.inf)):
        send(lambda e: e.tracker_output.MergeFrom(
            pb.TrackerOutput(frame_id=1, box=pb.ImageBox(**box), confidence=confidence)))
        expect_error(client, pb.ERROR_CODE_INVALID_ARGUMENT, fatal=False)

    # A box is in the subscribed camera's image, for a frame rendered: the
    # sim thread refuses others, not fatally (a kTrack UAV steers by boxes).
    client.send_tracker_output(1, 1.0, 2.0, 3.0, 4.0, 1.0)
    assert "subscribes to no camera" in expect_error(client, pb.ERROR_CODE_INVALID_ARGUMENT, fatal=False).message

    # Valid requests get no Error, and the connection still works.
    client.send_controls(CAR_ID, -1.0, 1.0, 0.0)
    client.subscribe("uav", ["rgb"], "lockstep")
    assert client.step_and_receive(FRAME_TIMEOUT_S).frame_id == 1
    client.send_tracker_output(1, 1.0, 2.0, 3.0, 4.0, 1.0)
    expect_state_next(client)
    assert client.step_and_receive(FRAME_TIMEOUT_S).frame_id == 2
    for frame_id, x, says in ((1, 1.0, "already reported frame 1"), (0, 1.0, "was never rendered"),
                              (3, 1.0, "was never rendered (the newest is 2)"),
                              (2, 5000.0, "lies far outside the 320x180 image of camera 'uav'")):
        client.send_tracker_output(frame_id, x, 2.0, 3.0, 4.0, 1.0)
        assert says in expect_error(client, pb.ERROR_CODE_INVALID_ARGUMENT, fatal=False).message


@pytest.mark.parametrize("case", ["before-hello", "garbage", "empty", "server-kind", "too-large"])
def test_fatal_protocol_errors(daemon, connect, case):
    client = raw_client(daemon)
    if case == "before-hello":
        envelope = pb.Envelope()
        envelope.get_state.SetInParent()
        client.send_envelope(envelope)
        expect_error(client, pb.ERROR_CODE_NOT_HANDSHAKEN, fatal=True)
        expect_closed(client)
        return
    hello = pb.Envelope()
    hello.hello.protocol_version = 1
    hello.hello.client_name = case
    hello.hello.token = access_token("tcp", "127.0.0.1", daemon.port)
    client.send_envelope(hello)
    assert client.receive_envelope(FRAME_TIMEOUT_S).WhichOneof("kind") == "welcome"
    if case == "garbage":
        client.send_raw(struct.pack("<I", 5) + b"\xff\xff\xff\xff\xff")
        code = pb.ERROR_CODE_MALFORMED_MESSAGE
    elif case == "empty":
        client.send_raw(struct.pack("<I", 0))
        code = pb.ERROR_CODE_UNEXPECTED_MESSAGE
    elif case == "server-kind":
        envelope = pb.Envelope()
        envelope.frame.frame_id = 1
        client.send_envelope(envelope)
        code = pb.ERROR_CODE_UNEXPECTED_MESSAGE
    else:
        client.send_raw(struct.pack("<I", (64 << 20) + 1))
        code = pb.ERROR_CODE_MESSAGE_TOO_LARGE
    expect_error(client, code, fatal=True)
    expect_closed(client)

    # Only that connection was closed.
    other = connect("still-alive")
    assert expect_state_next(other).entities


def test_max_message_bytes_flag(start_daemon):
    d = start_daemon("--max-message-bytes", "1000")
    client = raw_client(d)
    start_daemon.clients.append(client)
    hello = pb.Envelope()
    hello.hello.protocol_version = 1
    hello.hello.token = access_token("tcp", "127.0.0.1", d.port)
    client.send_envelope(hello)
    assert client.receive_envelope(FRAME_TIMEOUT_S).WhichOneof("kind") == "welcome"
    client.send_raw(struct.pack("<I", 1001))
    expect_error(client, pb.ERROR_CODE_MESSAGE_TOO_LARGE, fatal=True)
    expect_closed(client)


def test_too_many_clients(start_daemon):
    d = start_daemon("--max-clients", "1")
    first = sim4cv.Client()
    start_daemon.clients.append(first)
    first.connect("127.0.0.1", d.port, "first")
    second = raw_client(d)
    start_daemon.clients.append(second)
    expect_error(second, pb.ERROR_CODE_TOO_MANY_CLIENTS, fatal=True)
    expect_closed(second)
    assert expect_state_next(first).entities


# ---------------------------------------------------------------- state

def check_entity(e):
    for v in (e.position, e.linear_velocity, e.angular_velocity):
        assert all(math.isfinite(c) for c in (v.x, v.y, v.z)), e
    q = e.orientation
    assert math.sqrt(q.w ** 2 + q.x ** 2 + q.y ** 2 + q.z ** 2) == pytest.approx(1.0, abs=1e-6), e


def test_get_state(daemon, connect):
    client = connect("state")
    state = client.get_state()
    assert state.frame_id == 0
    assert [(e.id, e.name, e.kind) for e in state.entities] == [
        (CAR_ID, "car", pb.ENTITY_KIND_CAR), (UAV_ID, "uav", pb.ENTITY_KIND_UAV)]
    for e in state.entities:
        check_entity(e)
    start = {e.id: e.position for e in state.entities}

    client.subscribe("uav", ["boxes"], "lockstep")
    for _ in range(30):
        frame = client.step_and_receive(FRAME_TIMEOUT_S)
    state = client.get_state()
    assert state.frame_id == frame.frame_id == 30
    assert state.sim_time == pytest.approx(frame.sim_time)
    car = state.entities[0]
    assert car.name == "car"
    check_entity(car)
    moved = math.dist((car.position.x, car.position.y, car.position.z),
                      (start[CAR_ID].x, start[CAR_ID].y, start[CAR_ID].z))
    assert moved > 0, "the car did not move in one simulated second"


def test_tracker_output_appears_in_state(daemon, connect):
    client = connect("tracker")
    client.subscribe("uav", ["boxes"], "lockstep")
    frame = client.step_and_receive(FRAME_TIMEOUT_S)
    car = [b for b in frame.boxes if b.object_id == CAR_ID][0]
    client.send_tracker_output(frame.frame_id, car.x + 0.5, car.y + 0.25, car.width, car.height, 0.9)
    client.step_and_receive(FRAME_TIMEOUT_S)  # applied at the next simulation step
    out = client.get_state().last_tracker_output
    assert out.frame_id == frame.frame_id
    assert (out.box.x, out.box.y, out.box.width, out.box.height) == pytest.approx(
        (car.x + 0.5, car.y + 0.25, car.width, car.height))
    assert out.confidence == pytest.approx(0.9)


def test_controls_take_the_car(daemon, connect):
    client = connect("driver")
    client.subscribe("uav", ["boxes"], "lockstep")

    def car_speed():
        car = client.get_state().entities[0]
        assert car.id == CAR_ID
        return math.hypot(car.linear_velocity.x, car.linear_velocity.y)

    for _ in range(30):
        client.step_and_receive(FRAME_TIMEOUT_S)
    before = car_speed()
    client.send_controls(CAR_ID, 0.0, 0.0, 1.0)  # full brake
    for _ in range(60):
        client.step_and_receive(FRAME_TIMEOUT_S)
    after = car_speed()
    assert after < max(0.5, 0.5 * before), \
        "car speed %.2f m/s -> %.2f m/s after 2 s of full brake" % (before, after)


# ---------------------------------------------------------------- several clients

def test_disconnected_lockstep_client_does_not_stall(daemon, connect):
    a = connect("a")
    b = connect("b")
    a.subscribe("uav", ["boxes"], "lockstep")
    b.subscribe("uav", ["boxes"], "lockstep")
    a.step()
    with pytest.raises(TimeoutError):
        a.receive_frame(timeout=0.5)  # waits for b's Step
    b.step()
    assert a.receive_frame(FRAME_TIMEOUT_S).frame_id == 1
    assert b.receive_frame(FRAME_TIMEOUT_S).frame_id == 1
    b.close()
    assert a.step_and_receive(FRAME_TIMEOUT_S).frame_id == 2


def test_newest_delivery_counts_drops(daemon, connect):
    driver = connect("driver")
    viewer = connect("viewer")
    driver.subscribe("uav", ["boxes"], "lockstep")
    for _ in range(3):
        driver.step_and_receive(FRAME_TIMEOUT_S)
    before = viewer.get_state().frame_id
    assert before == 3
    viewer.subscribe("uav", ["rgb", "depth", "mask"], "newest")

    last = 0
    for _ in range(40):  # the viewer reads nothing meanwhile
        last = driver.step_and_receive(FRAME_TIMEOUT_S).frame_id
    received = 0
    while True:
        frame = viewer.receive_frame(FRAME_TIMEOUT_S)
        received += 1
        # Every frame since the subscription was either delivered or counted.
        assert received + frame.dropped_frames == frame.frame_id - before, (
            received, frame.dropped_frames, frame.frame_id)
        if frame.frame_id == last:
            break
    assert frame.dropped_frames > 0, "a viewer that read nothing for 40 frames dropped none"


def test_on_request_delivery_sends_the_newest_frame_when_asked(daemon, connect):
    driver = connect("driver")
    tracker = connect("tracker")
    driver.subscribe("uav", ["boxes"], "lockstep")
    tracker.subscribe("uav", ["rgb", "mask"], "on_request")
    for _ in range(5):
        last = driver.step_and_receive(FRAME_TIMEOUT_S).frame_id
    frame = tracker.request_frame(FRAME_TIMEOUT_S)
    # The newest frame, not the first one rendered. The sim thread offers a
    # frame to its subscribers one after the other, so the driver can hold
    # frame `last` a few microseconds before the tracker's mailbox does: the
    # frame before it is then the newest the daemon has for the tracker.
    assert frame.frame_id in (last - 1, last), "the newest frame, not the first one rendered"
    assert sim4cv.image_array(frame, pb.CHANNEL_RGB).shape == (180, 320, 3)
    with pytest.raises(TimeoutError):
        tracker.receive_frame(0.3)  # nothing arrives unasked
    following = driver.step_and_receive(FRAME_TIMEOUT_S).frame_id
    # The same race again: a newer frame than the one it had, the newest or the one before it.
    answered = tracker.request_frame(FRAME_TIMEOUT_S).frame_id
    assert answered in (following - 1, following) and answered > frame.frame_id, (answered, following)
    newest = connect("newest")
    newest.subscribe("uav", ["rgb"], "newest")
    with pytest.raises(sim4cv.ServerError) as refused:
        newest.request_frame(FRAME_TIMEOUT_S)
    assert "NextFrame needs an on-request subscription" in str(refused.value)
