"""A blocking TCP client for sim4cvd, written from docs/protocol.md alone.

    from sim4cv import Client, image_array
    with Client() as c:
        welcome = c.connect("127.0.0.1", port, "my-tracker")
        c.subscribe("uav", ["rgb", "boxes"], "lockstep")
        for _ in range(100):
            frame = c.step_and_receive()
            rgb = image_array(frame, "rgb")      # (h, w, 3) uint8, no copy

It also changes the world (docs/protocol.md, "Configuring the world"):

        uav = c.spawn("uav", "uav_b", 0, 0, 20)
        c.add_camera("uav_b_cam", mounted_on="uav_b", pitch_down_deg=45, gimbal=True)
        c.uav_velocity(uav, 2, 0, 0)

Wire format (docs/protocol.md, "Transport and framing"): every Envelope is
preceded by its serialized size as a 4-byte little-endian unsigned integer.
"""

import collections
import socket
import struct
import time

import numpy as np

from ._proto import pb
from .world import WorldRequests

PROTOCOL_VERSION = 1
LENGTH_PREFIX_BYTES = 4
DEFAULT_MAX_MESSAGE_BYTES = 64 << 20  # what we accept from the daemon: frames can be tens of MB

_PREFIX = struct.Struct("<I")

# Message kinds the server sends (Envelope oneof names).
_SERVER_KINDS = ("welcome", "subscribed", "frame", "state", "error", "stats", "configured")


class ServerError(Exception):
    """The daemon answered with an Error envelope.

    code       -- ErrorCode value (compare with sim4cv.pb.ERROR_CODE_*)
    message    -- the server's human-readable explanation
    fatal      -- True if the server has closed the connection after sending it
    request_id -- the Configure.request_id it answers; 0 for Errors about other messages
    """

    def __init__(self, code, message, fatal, request_id=0):
        self.code = int(code)
        self.message = message
        self.fatal = bool(fatal)
        self.request_id = int(request_id)
        super().__init__("%s%s: %s" % (self.code_name, " (fatal)" if self.fatal else "", message))

    @property
    def code_name(self):
        try:
            return pb.ErrorCode.Name(self.code)
        except ValueError:
            return "ERROR_CODE_%d" % self.code


class ConnectionClosed(ConnectionError):
    """The connection is closed (by the peer, by a fatal error, or by close())."""


class ProtocolError(ConnectionError):
    """The peer broke the framing (oversized prefix, unparsable bytes, or an
    envelope of a kind the server never sends). The connection is closed."""


# --------------------------------------------------------------------------
# Framing: pure functions plus a buffered reader over a socket.
# --------------------------------------------------------------------------

def encode_length_prefix(size):
    """The 4-byte little-endian prefix for a message of `size` bytes."""
    return _PREFIX.pack(size)


def decode_length_prefix(data):
    """The size encoded in the first 4 bytes of `data` (any bytes-like object)."""
    return _PREFIX.unpack_from(data)[0]


def encode_envelope(envelope):
    """Prefix + serialized bytes of `envelope`, ready to write to the stream."""
    payload = envelope.SerializeToString()
    return _PREFIX.pack(len(payload)) + payload


def decode_envelope(payload):
    """Parses an Envelope from a bytes-like object (bytes, bytearray, memoryview).
    Raises ProtocolError if the bytes are not a valid Envelope."""
    envelope = pb.Envelope()
    try:
        envelope.ParseFromString(payload)
    except Exception as e:  # google.protobuf.message.DecodeError and friends
        raise ProtocolError("received bytes that are not a valid Envelope: %s" % e) from e
    return envelope


class FramedSocket:
    """Length-prefixed Envelopes over a connected stream socket.

    Received bytes go into one preallocated bytearray with recv_into; an
    Envelope is parsed straight from a memoryview slice of it, so bytes are
    never copied between socket and parser. Small messages that arrive
    together are parsed from a single recv. A timeout in the middle of a
    message loses nothing: the partial bytes stay buffered for the next call.
    """

    def __init__(self, sock, max_message_bytes=DEFAULT_MAX_MESSAGE_BYTES, initial_buffer=1 << 20,
                 send_timeout=None):
        self.sock = sock
        self.send_timeout = send_timeout  # None: block until the kernel takes the bytes
        self.max_message_bytes = max_message_bytes
        self._buf = bytearray(max(initial_buffer, 64))
        self._view = memoryview(self._buf)
        self._start = 0  # first unconsumed byte
        self._end = 0    # one past the last received byte

    def send(self, envelope):
        self.send_raw(encode_envelope(envelope))

    def send_raw(self, data):
        # Receives leave a short per-call timeout on the socket; sends get their own.
        self.sock.settimeout(self.send_timeout)
        self.sock.sendall(data)

    def _fill(self, needed, deadline):
        """Ensures at least `needed` unconsumed bytes are buffered."""
        if len(self._buf) - self._start < needed:
            # Not enough room after _start: move the unconsumed bytes to the
            # front, growing the buffer if even that is too small.
            pending = self._end - self._start
            if len(self._buf) < needed:
                size = len(self._buf)
                while size < needed:
                    size *= 2
                new = bytearray(size)
                new[:pending] = self._view[self._start:self._end]
                self._view.release()
                self._buf = new
                self._view = memoryview(self._buf)
            else:
                self._view[:pending] = self._view[self._start:self._end]
            self._start, self._end = 0, pending
        while self._end - self._start < needed:
            if deadline is None:
                self.sock.settimeout(None)
            else:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise TimeoutError("timed out waiting for the server")
                self.sock.settimeout(remaining)
            try:
                n = self.sock.recv_into(self._view[self._end:])
            except socket.timeout as e:  # an alias of TimeoutError on 3.10+
                raise TimeoutError("timed out waiting for the server") from e
            except ConnectionResetError as e:
                raise ConnectionClosed("the server reset the connection") from e
            if n == 0:
                raise ConnectionClosed("the server closed the connection")
            self._end += n

    def receive(self, timeout=None):
        """The next Envelope. Raises TimeoutError (nothing consumed),
        ConnectionClosed, or ProtocolError."""
        deadline = None if timeout is None else time.monotonic() + timeout
        self._fill(LENGTH_PREFIX_BYTES, deadline)
        size = _PREFIX.unpack_from(self._buf, self._start)[0]
        if size > self.max_message_bytes:
            raise ProtocolError("server announced a %d-byte message, above the limit of %d bytes"
                                % (size, self.max_message_bytes))
        self._fill(LENGTH_PREFIX_BYTES + size, deadline)
        begin = self._start + LENGTH_PREFIX_BYTES
        payload = self._view[begin:begin + size]
        try:
            envelope = decode_envelope(payload)
        finally:
            payload.release()
        self._start = begin + size
        if self._start == self._end:
            self._start = self._end = 0
        return envelope


# --------------------------------------------------------------------------
# Enum helpers: accept enum values or short names ("rgb", "lockstep").
# --------------------------------------------------------------------------

def _enum_value(enum, prefix, value):
    if isinstance(value, str):
        name = value.upper()
        if not name.startswith(prefix):
            name = prefix + name
        try:
            return enum.Value(name)
        except ValueError:
            raise ValueError("unknown %s %r; expected one of %s" % (
                prefix.rstrip("_").lower(), value,
                ", ".join(n[len(prefix):].lower() for n in enum.keys() if not n.endswith("UNSPECIFIED")))) from None
    return int(value)


def channel_value(channel):
    """CHANNEL_* value for an int or a name such as "rgb", "DEPTH", "CHANNEL_MASK"."""
    return _enum_value(pb.Channel, "CHANNEL_", channel)


def delivery_value(delivery):
    """DELIVERY_* value for an int or a name such as "lockstep", "newest" or "on_request"."""
    return _enum_value(pb.Delivery, "DELIVERY_", delivery)


def entity_kind_value(kind):
    """ENTITY_KIND_* value for an int or a name such as "car" or "uav"."""
    return _enum_value(pb.EntityKind, "ENTITY_KIND_", kind)


# --------------------------------------------------------------------------
# Images
# --------------------------------------------------------------------------

# Image.element -> numpy dtype. Each Image says its element type and
# components, so any channel, including ones added after this client, can be
# viewed without a table of channels or formats.
_ELEMENTS = {
    pb.ELEMENT_TYPE_U8: np.dtype(np.uint8),
    pb.ELEMENT_TYPE_U16: np.dtype("<u2"),
    pb.ELEMENT_TYPE_F32: np.dtype("<f4"),
}


def find_image(frame, channel):
    """The Image of `channel` in `frame`, or None if the frame does not carry it."""
    channel = channel_value(channel)
    for image in frame.images:
        if image.channel == channel:
            return image
    return None


def image_array(frame, channel):
    """A numpy view of one channel's pixels, shaped by Image.element and
    Image.components: RGB -> (h, w, 3) uint8, DEPTH -> (h, w) float32 metres,
    MASK -> (h, w) uint16, SEMANTIC -> (h, w) uint8 class ids, NORMALS ->
    (h, w, 3) float32, FLOW -> (h, w, 2) float32 pixels (docs/protocol.md §8).

    The array wraps the received bytes without copying (honouring the row
    stride), so it is read-only; call .copy() to get a writable array.
    Raises KeyError if the frame does not carry the channel.
    """
    image = find_image(frame, channel)
    if image is None:
        raise KeyError("frame %d does not carry channel %s" % (
            frame.frame_id, pb.Channel.Name(channel_value(channel))))
    try:
        dtype = _ELEMENTS[image.element]
    except KeyError:
        raise ValueError("unsupported element type %d" % image.element) from None
    components = image.components
    if components < 1:
        raise ValueError("image of channel %s has %d components" % (pb.Channel.Name(image.channel), components))
    width, height, stride = frame.width, frame.height, image.stride
    data = image.data  # one bytes object; the array below keeps it alive
    row_bytes = width * components * dtype.itemsize
    if stride < row_bytes or (height and len(data) < (height - 1) * stride + row_bytes):
        raise ValueError("image of channel %s: %d bytes with stride %d do not hold %dx%d pixels" % (
            pb.Channel.Name(image.channel), len(data), stride, width, height))
    if components == 1:
        shape, strides = (height, width), (stride, dtype.itemsize)
    else:
        shape, strides = (height, width, components), (stride, components * dtype.itemsize, dtype.itemsize)
    return np.ndarray(shape, dtype=dtype, buffer=data, strides=strides)


# --------------------------------------------------------------------------
# Client
# --------------------------------------------------------------------------

class Client(WorldRequests):
    """One blocking TCP session with sim4cvd.

    Error envelopes are raised as ServerError from whichever call is reading
    when they arrive: Errors are not tied to a request, so an Error caused by
    e.g. send_controls() surfaces from the next receive_frame()/get_state().
    The exception are the answers to configure() (and the methods built on
    it), which carry its request_id: configure() raises only its own Error
    and keeps any other for the next call that reads. After a fatal error
    the client is closed.
    """

    def __init__(self, max_message_bytes=DEFAULT_MAX_MESSAGE_BYTES):
        self.max_message_bytes = max_message_bytes
        self.welcome = None
        self.subscribed = None
        self._conn = None
        # Frames read while waiting for something else, and Errors that
        # configure() read but that were not its answer, in arrival order.
        self._queued = collections.deque()
        self._last_request_id = 0

    # -- context manager ---------------------------------------------------
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def connected(self):
        return self._conn is not None

    # -- low level ---------------------------------------------------------
    def connect_raw(self, host, port, timeout=5.0):
        """Opens the TCP connection without the handshake."""
        self.close()
        self.attach(socket.create_connection((host, int(port)), timeout=timeout))

    def attach(self, sock):
        """Uses an already connected stream socket (no handshake); the client
        owns it from now on. For other stream transports and for tests."""
        self.close()
        if sock.family in (socket.AF_INET, socket.AF_INET6):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._conn = FramedSocket(sock, self.max_message_bytes)

    def send_envelope(self, envelope):
        self._require_connection().send(envelope)

    def send_raw(self, data):
        """Writes bytes exactly as given (for tests that misbehave on purpose)."""
        self._require_connection().send_raw(data)

    def receive_envelope(self, timeout=None):
        """The next Envelope of any kind, Errors included (not raised).
        Closes the client if the connection ends or the framing breaks."""
        conn = self._require_connection()
        try:
            return conn.receive(timeout)
        except (ConnectionClosed, ProtocolError, OSError) as e:
            if not isinstance(e, TimeoutError):
                self.close()
            raise

    def _require_connection(self):
        if self._conn is None:
            raise ConnectionClosed("not connected")
        return self._conn

    def _receive_kind(self, kind, timeout):
        """Reads until an envelope of `kind` arrives and returns its message.
        Frames read meanwhile are queued for receive_frame(); an Error (one
        queued by configure(), or one read now) is raised as ServerError."""
        for item in self._queued:
            if isinstance(item, pb.Error):
                self._queued.remove(item)
                self._raise(item)
        return self._receive_until(lambda envelope, which: which == kind, timeout, errors_interrupt=True)

    def _receive_until(self, wanted, timeout, errors_interrupt):
        """Reads until wanted(envelope, kind_name) and returns that envelope's
        message. Frames read meanwhile are queued; so are Errors unless
        `errors_interrupt` (fatal ones are always raised)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            envelope = self.receive_envelope(remaining)
            which = envelope.WhichOneof("kind")
            if wanted(envelope, which):
                return getattr(envelope, which)
            if which == "error":
                if errors_interrupt or envelope.error.fatal:
                    self._raise(envelope.error)
                self._queued.append(envelope.error)
            elif which == "frame":
                self._queued.append(envelope.frame)
            elif which in _SERVER_KINDS:
                pass  # e.g. a late Subscribed/State nobody waits for: ignore
            else:
                self.close()
                raise ProtocolError("server sent an envelope of kind %r" % which)

    def _raise(self, error):
        if error.fatal:
            self.close()
        raise ServerError(error.code, error.message, error.fatal, error.request_id)

    def _drop_queued_frames(self):
        self._queued = collections.deque(item for item in self._queued if isinstance(item, pb.Error))

    # -- session -----------------------------------------------------------
    def connect(self, host, port, name="python-client", timeout=5.0, protocol_version=PROTOCOL_VERSION):
        """Connects, sends Hello and returns the Welcome.
        Raises ServerError (e.g. VERSION_MISMATCH, TOO_MANY_CLIENTS)."""
        self.connect_raw(host, port, timeout)
        envelope = pb.Envelope()
        envelope.hello.protocol_version = protocol_version
        envelope.hello.client_name = name
        self.send_envelope(envelope)
        self.welcome = self._receive_kind("welcome", timeout)
        return self.welcome

    def subscribe(self, camera, channels, delivery, with_state=False, timeout=5.0):
        """Subscribes (replacing any earlier subscription) and returns the
        Subscribed acknowledgement. Frames of the replaced subscription that
        were still queued or arrive before the acknowledgement are discarded.
        channels: iterable of Channel values or names ("rgb", "depth", "mask", "boxes").
        delivery: a Delivery value or "lockstep" / "newest"."""
        envelope = pb.Envelope()
        envelope.subscribe.camera = camera
        envelope.subscribe.channels.extend(channel_value(c) for c in channels)
        envelope.subscribe.delivery = delivery_value(delivery)
        envelope.subscribe.with_state = with_state
        self.send_envelope(envelope)
        self._drop_queued_frames()
        subscribed = self._receive_kind("subscribed", timeout)
        self._drop_queued_frames()  # frames read before Subscribed belong to the old subscription
        self.subscribed = subscribed
        return subscribed

    def step(self):
        """Lockstep: grants the simulation one more frame for this client."""
        envelope = pb.Envelope()
        envelope.step.SetInParent()
        self.send_envelope(envelope)

    def receive_frame(self, timeout=10.0):
        """The next Frame (queued ones first). Raises TimeoutError if none
        arrives in `timeout` seconds (None: wait forever), ServerError if an
        Error arrives (or was queued) first."""
        if self._queued:
            item = self._queued.popleft()
            if isinstance(item, pb.Error):
                self._raise(item)
            return item
        return self._receive_kind("frame", timeout)

    def step_and_receive(self, timeout=10.0):
        """step() then receive_frame()."""
        self.step()
        return self.receive_frame(timeout)

    def request_frame(self, timeout=10.0):
        """On-request delivery ("on_request"): asks for a frame (NextFrame)
        and returns it: the newest this client was not sent yet, else the
        next one rendered, so at most one frame period plus its transfer
        old. Raises TimeoutError, or ServerError if the subscription is not
        on request."""
        envelope = pb.Envelope()
        envelope.next_frame.SetInParent()
        self.send_envelope(envelope)
        return self.receive_frame(timeout)

    def send_tracker_output(self, frame_id, x, y, w, h, confidence):
        """Reports a tracker's box (pixels, top-left origin) for a frame.
        No reply; an invalid value comes back later as INVALID_ARGUMENT."""
        envelope = pb.Envelope()
        out = envelope.tracker_output
        out.frame_id = frame_id
        out.box.x, out.box.y, out.box.width, out.box.height = x, y, w, h
        out.confidence = confidence
        self.send_envelope(envelope)

    def send_controls(self, entity_id, steering, throttle, brake):
        """Drives a car (steering -1..1, throttle 0..1, brake 0..1). No reply;
        errors (UNKNOWN_ENTITY, INVALID_ARGUMENT) come back later."""
        envelope = pb.Envelope()
        c = envelope.controls
        c.entity_id, c.steering, c.throttle, c.brake = entity_id, steering, throttle, brake
        self.send_envelope(envelope)

    def get_state(self, timeout=5.0):
        """Asks for and returns a State snapshot. Frames arriving meanwhile
        are kept for receive_frame()."""
        envelope = pb.Envelope()
        envelope.get_state.SetInParent()
        self.send_envelope(envelope)
        return self._receive_kind("state", timeout)

    # -- configuring the world (docs/protocol.md, "Configuring the world") --
    def configure(self, request, timeout=30.0):
        """Sends a pb.Configure (its request_id replaced by the next one) and
        returns the pb.Configured answering it. Raises ServerError (with
        .request_id) if the daemon refuses it, TimeoutError if no answer
        comes. Frames, and Errors that are not this request's answer (e.g.
        UNKNOWN_CAMERA for a subscription whose camera was just removed),
        are kept for the next call that reads."""
        self._last_request_id = self._last_request_id % 0xFFFFFFFF + 1  # never 0
        request_id = self._last_request_id
        envelope = pb.Envelope()
        envelope.configure.CopyFrom(request)
        envelope.configure.request_id = request_id
        self.send_envelope(envelope)

        def answers(reply, which):
            return which in ("configured", "error") and getattr(reply, which).request_id == request_id

        answer = self._receive_until(answers, timeout, errors_interrupt=False)
        if isinstance(answer, pb.Error):
            self._raise(answer)
        return answer

    def close(self):
        """Closes the connection (the server drops the session at once).
        Safe to call more than once."""
        conn, self._conn = self._conn, None
        self._queued.clear()
        if conn is not None:
            try:
                conn.sock.close()
            except OSError:
                pass
