"""The API every transport offers (TcpClient, UdpClient, ShmClient):
handshake, subscription, frames, requests, world configuration, reconnect.

A transport implements the hooks at the bottom (_open, _close, _send,
_exchange, _next_frame, _newest_frame, _configure); everything else, the
messages themselves included, lives here once.
"""

import time
from typing import Iterable, Iterator, Optional

from ._proto import pb
from .access import access_token
from .address import Address, parse_address
from .errors import ConnectionClosed, ServerError
from .frame import Frame
from .framing import PROTOCOL_VERSION
from .images import channel_value, delivery_value
from .world import WorldRequests

RETRY_INTERVAL_S = 0.25  # UDP request retries, reconnect attempts
KEEPALIVE_INTERVAL_S = 1.0  # UDP and shm: send something after this much silence


def envelope(**fields) -> "pb.Envelope":
    """pb.Envelope with one message set, e.g. envelope(step=pb.Step())."""
    return pb.Envelope(**fields)


class BaseClient(WorldRequests):
    """A blocking session with sim4cvd over one transport; see sim4cv.connect().

    Calls are not thread-safe. Errors the daemon sends are raised as
    ServerError from the call that reads them (Errors are not tied to a
    request, except configure()'s). With reconnect=True a lost connection
    (ConnectionClosed) is re-established by the call that notices it: the
    client connects to the same address again (retrying for `timeout`
    seconds), re-sends Hello and the last Subscribe, and carries on.
    """

    transport = "?"

    def __init__(self, address, name: str = "python-client", timeout: float = 5.0, reconnect: bool = False):
        self.address: Address = address if isinstance(address, Address) else parse_address(address)
        if self.address.transport != self.transport:
            raise ValueError("%s cannot serve %s" % (type(self).__name__, self.address))
        self.name = name
        self.timeout = float(timeout)
        self.reconnect = bool(reconnect)
        self.welcome: Optional[pb.Welcome] = None
        self.subscribed: Optional[pb.Subscribed] = None
        self.reconnects = 0  # how often reconnect=True re-established the session
        self._subscription: Optional[pb.Subscribe] = None  # the last Subscribe sent
        self._steps_outstanding = 0  # Steps sent that no frame answered yet
        self._request_id = 0
        self._open_now = False
        self._closed_by_user = False
        # Hello.token; None: SIM4CV_TOKEN or the daemon's token file (sim4cv.access)
        self.token: Optional[str] = None

    # -- context manager ---------------------------------------------------
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return "<%s %s%s>" % (type(self).__name__, self.address, "" if self._open_now else " closed")

    # -- session -----------------------------------------------------------
    def connect(self) -> "pb.Welcome":
        """Opens the transport (if needed) and sends Hello; returns the Welcome."""
        return self.hello()

    def hello(self, timeout: Optional[float] = None, protocol_version: int = PROTOCOL_VERSION) -> "pb.Welcome":
        """Sends Hello (opening or re-attaching the transport first if needed)
        and returns the Welcome (also .welcome). Raises ConnectionClosed
        naming the address if the daemon cannot be reached in `timeout`."""
        timeout = self.timeout if timeout is None else timeout
        self._closed_by_user = False
        if not self._open_now:
            self._open(timeout)
            self._open_now = True
        token = self.token
        if token is None:
            # shm admits only the daemon's own user (peer credentials) and needs none
            token = access_token(self.address.transport, self.address.host, self.address.port) \
                if self.address.transport != "shm" else ""
        hello = envelope(hello=pb.Hello(protocol_version=protocol_version, client_name=self.name, token=token))
        try:
            self.welcome = self._exchange(hello, "welcome", timeout)
        except TimeoutError as e:
            self.close()
            raise ConnectionClosed("no Welcome from sim4cvd at %s (%s) within %.1f s" % (
                self.address, self.transport.upper(), timeout)) from e
        except ServerError:
            raise
        except ConnectionClosed:
            self.close()
            raise
        return self.welcome

    def subscribe(self, camera: str, channels: Iterable, delivery, with_state: bool = False,
                  timeout: Optional[float] = None) -> "pb.Subscribed":
        """Subscribes to `camera` (replacing any earlier subscription) and
        returns the Subscribed acknowledgement. channels: Channel values or
        names ("rgb", "depth", "mask", "boxes", ...); delivery: a Delivery
        value or "lockstep" / "newest" / "on_request". Over shared memory
        the camera must be the ring's camera."""
        request = pb.Subscribe(camera=camera, channels=[channel_value(c) for c in channels],
                               delivery=delivery_value(delivery), with_state=with_state)
        timeout = self.timeout if timeout is None else timeout
        self.subscribed = self._call(lambda: self._exchange(envelope(subscribe=request), "subscribed", timeout))
        self._subscription = request
        self._steps_outstanding = 0
        return self.subscribed

    @property
    def delivery(self) -> Optional[int]:
        """The Delivery value of the current subscription (None: none)."""
        return None if self._subscription is None else self._subscription.delivery

    def step(self) -> None:
        """Lockstep: grants the simulation one more frame for this client."""
        self._call(self._step)

    def _step(self):
        self._send(envelope(step=pb.Step()))
        self._steps_outstanding += 1

    def receive_frame(self, timeout: Optional[float] = 10.0, copy: bool = False) -> Frame:
        """The next frame. Raises TimeoutError if none arrives in `timeout`
        seconds (None: wait forever), ServerError if an Error comes first.
        copy=True: a frame that owns its pixels (matters over shared memory)."""
        return self._call(lambda: self._got_frame(self._next_frame(timeout, copy)), resend_steps=True)

    def step_and_receive(self, timeout: Optional[float] = 10.0, copy: bool = False) -> Frame:
        """step() then receive_frame()."""
        def step_then_receive():
            self._step()
            return self._got_frame(self._next_frame(timeout, copy))
        return self._call(step_then_receive)

    def request_frame(self, timeout: Optional[float] = 10.0, copy: bool = False) -> Frame:
        """On-request delivery: the newest frame this client has not had yet,
        else the next one rendered (TCP/UDP: a NextFrame request, repeated
        every 0.25 s over UDP; shared memory: the newest ring slot newer than
        the last frame returned)."""
        return self._call(lambda: self._got_frame(self._newest_frame(timeout, copy)))

    def frames(self, step: Optional[bool] = None, count: Optional[int] = None, timeout: Optional[float] = 10.0,
               copy: bool = False) -> Iterator[Frame]:
        """Iterates over frames: step_and_receive() each time if `step`
        (default: when the subscription is lockstep), request_frame() for an
        on-request subscription, else receive_frame(). count None: forever."""
        if step is None:
            step = self.delivery == pb.DELIVERY_LOCKSTEP
        on_request = self.delivery == pb.DELIVERY_ON_REQUEST
        n = 0
        while count is None or n < count:
            if step:
                yield self.step_and_receive(timeout, copy)
            elif on_request:
                yield self.request_frame(timeout, copy)
            else:
                yield self.receive_frame(timeout, copy)
            n += 1

    def send_tracker_output(self, frame_id: int, x: float, y: float, w: float, h: float,
                            confidence: float) -> None:
        """Reports a tracker's box (pixels, top-left origin) for a frame. No
        reply; an invalid value comes back later as INVALID_ARGUMENT."""
        out = pb.TrackerOutput(frame_id=frame_id, box=pb.ImageBox(x=x, y=y, width=w, height=h),
                               confidence=confidence)
        self._call(lambda: self._send(envelope(tracker_output=out)))

    def send_controls(self, entity_id: int, steering: float, throttle: float, brake: float) -> None:
        """Drives a car (steering -1..1, throttle 0..1, brake 0..1). No reply."""
        controls = pb.Controls(entity_id=entity_id, steering=steering, throttle=throttle, brake=brake)
        self._call(lambda: self._send(envelope(controls=controls)))

    def get_state(self, timeout: Optional[float] = None) -> "pb.State":
        """A State snapshot (every entity's pose and velocity)."""
        timeout = self.timeout if timeout is None else timeout
        return self._call(lambda: self._exchange(envelope(get_state=pb.GetState()), "state", timeout))

    def get_stats(self, timeout: Optional[float] = None) -> "pb.Stats":
        """The daemon's counters (pb.Stats; .counters is a name -> value map)."""
        timeout = self.timeout if timeout is None else timeout
        return self._call(lambda: self._exchange(envelope(get_stats=pb.GetStats()), "stats", timeout))

    def configure(self, request: "pb.Configure", timeout: float = 30.0) -> "pb.Configured":
        """Sends a pb.Configure (its request_id replaced by the next one) and
        returns the pb.Configured answering it; ServerError (with
        .request_id) if the daemon refuses it, TimeoutError if no answer
        comes. The world helpers (spawn, add_camera, ...) build on it."""
        self._request_id = self._request_id % 0xFFFFFFFF + 1  # never 0
        request_id = self._request_id
        return self._call(lambda: self._configure(request, request_id, timeout))

    def close(self) -> None:
        """Ends the session and frees the transport. Safe to call twice;
        hello() opens it again."""
        self._closed_by_user = True
        self._open_now = False
        self._close()

    @property
    def connected(self) -> bool:
        return self._open_now

    # -- reconnect ---------------------------------------------------------
    def _got_frame(self, frame):
        if self._steps_outstanding:
            self._steps_outstanding -= 1
        return frame

    def _call(self, operation, resend_steps=False):
        """Runs `operation`; with reconnect=True, a ConnectionClosed makes it
        reconnect (Hello, last Subscribe) and run the operation once more."""
        if not self._open_now and (self._closed_by_user or not self.reconnect):
            raise ConnectionClosed("not connected to %s (call hello(), or close() was called)" % (self.address,))
        try:
            if not self._open_now:
                raise ConnectionClosed("not connected to %s" % (self.address,))
            return operation()
        except ConnectionClosed:
            if not self.reconnect:
                self._open_now = False
                raise
        self._reestablish(resend_steps)
        return operation()

    def _reestablish(self, resend_steps):
        steps = self._steps_outstanding if resend_steps else 0
        self._open_now = False
        self._close()
        deadline = time.monotonic() + max(self.timeout, 1.0)
        while True:
            try:
                self.hello()
                break
            except ConnectionClosed:
                if time.monotonic() >= deadline:
                    raise
                time.sleep(RETRY_INTERVAL_S)
        self.reconnects += 1
        self._steps_outstanding = 0
        if self._subscription is not None:
            self.subscribed = self._exchange(envelope(subscribe=self._subscription), "subscribed", self.timeout)
        for _ in range(steps):
            self._step()

    # -- transport hooks ---------------------------------------------------
    def _open(self, timeout):
        """Opens the transport; ConnectionClosed naming the address if it cannot."""
        raise NotImplementedError

    def _close(self):
        raise NotImplementedError

    def _send(self, env):
        """Sends an Envelope that has no reply."""
        raise NotImplementedError

    def _exchange(self, env, kind, timeout):
        """Sends `env` and returns the message of the first reply of `kind`
        (Envelope oneof name); raises ServerError on an Error, TimeoutError."""
        raise NotImplementedError

    def _next_frame(self, timeout, copy) -> Frame:
        raise NotImplementedError

    def _newest_frame(self, timeout, copy) -> Frame:
        raise NotImplementedError

    def _configure(self, request, request_id, timeout):
        raise NotImplementedError
