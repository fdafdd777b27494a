"""Unit tests of the Python client's framing, encoding and decoding, using a
socketpair as the "server" (no daemon needed)."""

import os
import socket
import struct
import sys
import threading
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv import pb  # noqa: E402
from sim4cv.client import FramedSocket  # noqa: E402


@pytest.fixture
def pair():
    a, b = socket.socketpair()
    yield a, b
    a.close()
    b.close()


def framed(envelope):
    payload = envelope.SerializeToString()
    return struct.pack("<I", len(payload)) + payload


def read_envelope(sock, timeout=5.0):
    """Reads one length-prefixed Envelope from the fake server's side."""
    sock.settimeout(timeout)

    def exact(n):
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise EOFError
            data += chunk
        return data

    size = struct.unpack("<I", exact(4))[0]
    envelope = pb.Envelope()
    envelope.ParseFromString(exact(size))
    return envelope


def error_envelope(code, message, fatal):
    envelope = pb.Envelope()
    envelope.error.code = code
    envelope.error.message = message
    envelope.error.fatal = fatal
    return envelope


def frame_envelope(frame_id, width=4, height=3):
    envelope = pb.Envelope()
    f = envelope.frame
    f.frame_id = frame_id
    f.camera = "uav"
    f.width, f.height = width, height
    return envelope


# ---------------------------------------------------------------- pure functions

def test_length_prefix_is_little_endian():
    assert sim4cv.encode_length_prefix(0x01020304) == b"\x04\x03\x02\x01"
    assert sim4cv.encode_length_prefix(0) == b"\x00\x00\x00\x00"
    assert sim4cv.encode_length_prefix(0xFFFFFFFF) == b"\xff\xff\xff\xff"
    assert sim4cv.decode_length_prefix(b"\x04\x03\x02\x01") == 0x01020304
    assert sim4cv.decode_length_prefix(memoryview(bytearray(b"\x00\x00\x00\x04extra"))) == 1 << 26


def test_encode_envelope_prefixes_serialized_bytes():
    envelope = pb.Envelope()
    envelope.hello.protocol_version = 1
    envelope.hello.client_name = "unit"
    data = sim4cv.encode_envelope(envelope)
    payload = envelope.SerializeToString()
    assert data == struct.pack("<I", len(payload)) + payload
    assert sim4cv.decode_envelope(memoryview(data)[4:]) == envelope


def test_empty_step_envelope_bytes():
    # Step has no fields: field 5, wire type 2, length 0 -> 0x2a 0x00.
    envelope = pb.Envelope()
    envelope.step.SetInParent()
    assert sim4cv.encode_envelope(envelope) == b"\x02\x00\x00\x00\x2a\x00"


def test_decode_garbage_raises_protocol_error():
    with pytest.raises(sim4cv.ProtocolError):
        sim4cv.decode_envelope(b"\xff\xff\xff\xff\xff")


def test_channel_and_delivery_names():
    assert sim4cv.channel_value("rgb") == pb.CHANNEL_RGB
    assert sim4cv.channel_value("CHANNEL_MASK") == pb.CHANNEL_MASK
    assert sim4cv.channel_value(pb.CHANNEL_DEPTH) == pb.CHANNEL_DEPTH
    assert sim4cv.delivery_value("newest") == pb.DELIVERY_NEWEST
    with pytest.raises(ValueError, match="depth"):
        sim4cv.channel_value("colour")


# ---------------------------------------------------------------- FramedSocket

def test_receive_reassembles_byte_by_byte_writes(pair):
    a, b = pair
    conn = FramedSocket(a)
    data = framed(frame_envelope(7))

    def writer():
        for i in range(len(data)):
            b.send(data[i:i + 1])
            time.sleep(0.001)

    t = threading.Thread(target=writer)
    t.start()
    envelope = conn.receive(timeout=5)
    t.join()
    assert envelope.frame.frame_id == 7


def test_receive_many_messages_from_one_write(pair):
    a, b = pair
    conn = FramedSocket(a, initial_buffer=64)  # small buffer: forces compaction
    b.sendall(b"".join(framed(frame_envelope(i)) for i in range(1, 51)))
    assert [conn.receive(timeout=5).frame.frame_id for _ in range(50)] == list(range(1, 51))


def test_receive_grows_buffer_for_large_message(pair):
    a, b = pair
    conn = FramedSocket(a, initial_buffer=1024)
    envelope = frame_envelope(3, 640, 480)
    image = envelope.frame.images.add()
    image.channel, image.format, image.stride = pb.CHANNEL_RGB, pb.PIXEL_FORMAT_RGB8, 640 * 3
    image.data = os.urandom(640 * 480 * 3)
    data = framed(envelope)
    t = threading.Thread(target=b.sendall, args=(data,))
    t.start()
    got = conn.receive(timeout=5)
    t.join()
    assert got == envelope


def test_zero_length_message_is_an_empty_envelope(pair):
    a, b = pair
    b.sendall(b"\x00\x00\x00\x00")
    assert FramedSocket(a).receive(timeout=5).WhichOneof("kind") is None


def test_timeout_mid_message_loses_nothing(pair):
    a, b = pair
    conn = FramedSocket(a)
    data = framed(frame_envelope(42))
    b.sendall(data[:3])
    with pytest.raises(TimeoutError):
        conn.receive(timeout=0.05)
    b.sendall(data[3:9])
    with pytest.raises(TimeoutError):
        conn.receive(timeout=0.05)
    b.sendall(data[9:])
    assert conn.receive(timeout=5).frame.frame_id == 42


def test_oversized_prefix_is_refused(pair):
    a, b = pair
    conn = FramedSocket(a, max_message_bytes=100)
    b.sendall(struct.pack("<I", 101))
    with pytest.raises(sim4cv.ProtocolError, match="101"):
        conn.receive(timeout=5)


def test_peer_close_raises_connection_closed(pair):
    a, b = pair
    conn = FramedSocket(a)
    b.sendall(framed(frame_envelope(1))[:5])  # close in the middle of a message
    b.close()
    with pytest.raises(sim4cv.ConnectionClosed):
        conn.receive(timeout=5)


def test_unparsable_payload_raises_protocol_error(pair):
    a, b = pair
    b.sendall(b"\x03\x00\x00\x00\xff\xff\xff")
    with pytest.raises(sim4cv.ProtocolError):
        FramedSocket(a).receive(timeout=5)


# ---------------------------------------------------------------- Client over a fake server

@pytest.fixture
def client_and_server(pair):
    a, b = pair
    client = sim4cv.Client()
    client.attach(a)
    yield client, b
    client.close()


def run_server(script):
    """Runs `script` (a function) in a thread; returns a join() that re-raises."""
    errors = []

    def body():
        try:
            script()
        except BaseException as e:  # noqa: BLE001 - reported in the test thread
            errors.append(e)

    t = threading.Thread(target=body)
    t.start()

    def join():
        t.join(10)
        assert not t.is_alive(), "fake server did not finish"
        if errors:
            raise errors[0]

    return join


def test_handshake_sends_hello_and_returns_welcome(pair):
    a, b = pair
    client = sim4cv.Client()
    client.attach(a)

    def server():
        hello = read_envelope(b)
        assert hello.hello.protocol_version == 1
        assert hello.hello.client_name == "unit"
        welcome = pb.Envelope()
        welcome.welcome.protocol_version = 1
        welcome.welcome.scene_name = "default"
        b.sendall(framed(welcome))

    join = run_server(server)
    # connect() opens TCP itself; exercise the same path after attach().
    envelope = pb.Envelope()
    envelope.hello.protocol_version = sim4cv.PROTOCOL_VERSION
    envelope.hello.client_name = "unit"
    client.send_envelope(envelope)
    welcome = client._receive_kind("welcome", 5)
    join()
    assert welcome.scene_name == "default"


def test_error_envelope_raises_server_error(client_and_server):
    client, b = client_and_server
    b.sendall(framed(error_envelope(pb.ERROR_CODE_UNKNOWN_CAMERA, "no camera 'x'; cameras: uav", False)))
    with pytest.raises(sim4cv.ServerError) as info:
        client.receive_frame(timeout=5)
    assert info.value.code == pb.ERROR_CODE_UNKNOWN_CAMERA
    assert info.value.code_name == "ERROR_CODE_UNKNOWN_CAMERA"
    assert not info.value.fatal
    assert "cameras: uav" in str(info.value)
    assert client.connected
    b.sendall(framed(frame_envelope(5)))
    assert client.receive_frame(timeout=5).frame_id == 5


def test_fatal_error_closes_the_client(client_and_server):
    client, b = client_and_server
    b.sendall(framed(error_envelope(pb.ERROR_CODE_VERSION_MISMATCH, "server 1, client 2", True)))
    with pytest.raises(sim4cv.ServerError) as info:
        client.receive_frame(timeout=5)
    assert info.value.fatal
    assert not client.connected
    with pytest.raises(sim4cv.ConnectionClosed):
        client.step()


def test_step_sends_step_envelope(client_and_server):
    client, b = client_and_server
    client.step()
    assert read_envelope(b).WhichOneof("kind") == "step"


def test_get_state_keeps_frames_that_arrive_first(client_and_server):
    client, b = client_and_server

    def server():
        assert read_envelope(b).WhichOneof("kind") == "get_state"
        state = pb.Envelope()
        state.state.frame_id = 9
        b.sendall(framed(frame_envelope(8)) + framed(frame_envelope(9)) + framed(state))

    join = run_server(server)
    state = client.get_state(timeout=5)
    join()
    assert state.frame_id == 9
    assert client.receive_frame(timeout=5).frame_id == 8
    assert client.receive_frame(timeout=5).frame_id == 9


def test_subscribe_encodes_request_and_drops_old_frames(client_and_server):
    client, b = client_and_server

    def server():
        request = read_envelope(b).subscribe
        assert request.camera == "uav"
        assert list(request.channels) == [pb.CHANNEL_RGB, pb.CHANNEL_BOXES]
        assert request.delivery == pb.DELIVERY_NEWEST
        assert request.with_state
        reply = pb.Envelope()
        reply.subscribed.camera = request.camera
        reply.subscribed.channels.extend(request.channels)
        reply.subscribed.delivery = request.delivery
        # A frame of the previous subscription, then the ack, then a new frame.
        b.sendall(framed(frame_envelope(1)) + framed(reply) + framed(frame_envelope(2)))

    join = run_server(server)
    subscribed = client.subscribe("uav", ["rgb", pb.CHANNEL_BOXES], "newest", with_state=True, timeout=5)
    join()
    assert subscribed.delivery == pb.DELIVERY_NEWEST
    assert client.receive_frame(timeout=5).frame_id == 2


def test_tracker_output_and_controls_encoding(client_and_server):
    client, b = client_and_server
    client.send_tracker_output(12, 1.5, 2.5, 30.0, 40.0, 0.75)
    client.send_controls(1, -0.5, 1.0, 0.0)
    out = read_envelope(b).tracker_output
    assert (out.frame_id, out.box.x, out.box.y, out.box.width, out.box.height, out.confidence) == (
        12, 1.5, 2.5, 30.0, 40.0, 0.75)
    controls = read_envelope(b).controls
    assert (controls.entity_id, controls.steering, controls.throttle, controls.brake) == (1, -0.5, 1.0, 0.0)


def test_receive_frame_timeout(client_and_server):
    client, _ = client_and_server
    start = time.monotonic()
    with pytest.raises(TimeoutError):
        client.receive_frame(timeout=0.1)
    assert time.monotonic() - start < 20  # the 0.1 s timeout was kept, not a blocking read (margin for busy hosts)
    assert client.connected


def test_server_closing_is_connection_closed(client_and_server):
    client, b = client_and_server
    b.close()
    with pytest.raises(sim4cv.ConnectionClosed):
        client.receive_frame(timeout=5)
    assert not client.connected


# ---------------------------------------------------------------- image_array

def make_frame(width, height, stride_padding=0):
    frame = pb.Frame(frame_id=1, width=width, height=height)
    rgb = np.arange(height * width * 3, dtype=np.uint8).reshape(height, width, 3)
    depth = np.linspace(0.5, 100, height * width, dtype="<f4").reshape(height, width)
    depth[0, 0] = np.inf
    mask = (np.arange(height * width, dtype="<u2") % 7).reshape(height, width)
    for channel, fmt, element, components, array in (
            (pb.CHANNEL_RGB, pb.PIXEL_FORMAT_RGB8, pb.ELEMENT_TYPE_U8, 3, rgb),
            (pb.CHANNEL_DEPTH, pb.PIXEL_FORMAT_DEPTH_F32, pb.ELEMENT_TYPE_F32, 1, depth),
            (pb.CHANNEL_MASK, pb.PIXEL_FORMAT_INSTANCE_U16, pb.ELEMENT_TYPE_U16, 1, mask)):
        row = array.reshape(height, -1).view(np.uint8)
        padded = np.zeros((height, row.shape[1] + stride_padding), np.uint8)
        padded[:, :row.shape[1]] = row
        frame.images.add(channel=channel, format=fmt, element=element, components=components,
                         stride=padded.shape[1], data=padded.tobytes())
    return frame, rgb, depth, mask


@pytest.mark.parametrize("padding", [0, 8])
def test_image_array_shapes_and_values(padding):
    frame, rgb, depth, mask = make_frame(5, 4, padding)
    got_rgb = sim4cv.image_array(frame, pb.CHANNEL_RGB)
    got_depth = sim4cv.image_array(frame, "depth")
    got_mask = sim4cv.image_array(frame, "mask")
    assert got_rgb.shape == (4, 5, 3) and got_rgb.dtype == np.uint8
    assert got_depth.shape == (4, 5) and got_depth.dtype == np.float32
    assert got_mask.shape == (4, 5) and got_mask.dtype == np.uint16
    np.testing.assert_array_equal(got_rgb, rgb)
    np.testing.assert_array_equal(got_depth, depth)
    np.testing.assert_array_equal(got_mask, mask)
    assert np.isinf(got_depth[0, 0])
    # A view on the received bytes, not a copy.
    assert not got_rgb.flags.writeable and not got_rgb.flags.owndata


def test_image_array_missing_channel_and_short_data():
    frame, _, _, _ = make_frame(5, 4)
    del frame.images[2]
    with pytest.raises(KeyError, match="CHANNEL_MASK"):
        sim4cv.image_array(frame, "mask")
    frame.images[0].data = frame.images[0].data[:-1]
    with pytest.raises(ValueError):
        sim4cv.image_array(frame, "rgb")
