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

This is the low-level TCP client that returns protobuf messages;
sim4cv.connect("tcp://...") wraps it in the common API of every transport
(sim4cv.TcpClient, returning sim4cv.Frame objects).
Wire format (docs/protocol.md, "Transport and framing"): framing.py.
"""

import collections
import socket
import time

from ._proto import pb
from .access import access_token
from .errors import ConnectionClosed, ProtocolError, ServerError  # noqa: F401 (re-exported)
from .framing import (  # noqa: F401 (re-exported for existing users of sim4cv.client)
    DEFAULT_MAX_MESSAGE_BYTES, LENGTH_PREFIX_BYTES, PROTOCOL_VERSION, FramedSocket, decode_envelope,
    decode_length_prefix, encode_envelope, encode_length_prefix)
from .images import (  # noqa: F401 (re-exported)
    channel_value, delivery_value, entity_kind_value, find_image, image_array)
from .world import WorldRequests

# Message kinds the server sends (Envelope oneof names).
_SERVER_KINDS = ("welcome", "subscribed", "frame", "state", "error", "stats", "configured")


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
    def connect(self, host, port, name="python-client", timeout=5.0, protocol_version=PROTOCOL_VERSION, token=None):
        """Connects, sends Hello and returns the Welcome.
        Raises ServerError (e.g. VERSION_MISMATCH, TOO_MANY_CLIENTS, UNAUTHENTICATED).
        token: Hello.token; None: SIM4CV_TOKEN or the daemon's token file (sim4cv.access)."""
        self.connect_raw(host, port, timeout)
        envelope = pb.Envelope()
        envelope.hello.protocol_version = protocol_version
        envelope.hello.client_name = name
        envelope.hello.token = access_token("tcp", host, port) if token is None else token
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
