"""The common client API over UDP (docs/protocol.md section 12): one
Envelope per datagram, numbered with Envelope.sequence; requests with a
reply retried every 0.25 s until answered; frames reassembled from
FrameChunks; keep-alives so that the registration does not lapse."""

import collections
import socket
import time

from ._proto import pb
from .base import KEEPALIVE_INTERVAL_S, RETRY_INTERVAL_S, BaseClient, envelope
from .errors import ConnectionClosed, ServerError
from .frame import Frame
from .reassembly import FrameReassembler

_REPLY_KINDS = ("welcome", "subscribed", "state", "stats", "configured", "error")
_MAX_DATAGRAM = 65536
_DRAIN_LIMIT = 4096  # datagrams read without blocking in one go


def open_datagram_socket(host, port, receive_buffer_bytes):
    """A UDP socket connected to (host, port), IPv4 preferred, with a large
    receive buffer (SO_RCVBUFFORCE where permitted, else SO_RCVBUF)."""
    infos = socket.getaddrinfo(host, port, 0, socket.SOCK_DGRAM)
    infos.sort(key=lambda info: info[0] != socket.AF_INET)
    family, kind, proto, _, sockaddr = infos[0]
    sock = socket.socket(family, kind, proto)
    try:
        try:
            sock.setsockopt(socket.SOL_SOCKET, getattr(socket, "SO_RCVBUFFORCE", 33), receive_buffer_bytes)
        except OSError:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer_bytes)
        sock.connect(sockaddr)
    except OSError:
        sock.close()
        raise
    return sock


class UdpClient(BaseClient):
    """sim4cv.connect("udp://HOST:PORT"): one connected UDP socket.

    Client-side counters: .reassembler.dropped (frames lost because a chunk
    never came), .reassembler.completed, .malformed (datagrams that did not
    parse). A lockstep receive_frame() that sees nothing for `step_retry_s`
    with no frame in progress sends another Step (the lost frame is not
    resent; frame_id skips)."""

    transport = "udp"

    def __init__(self, address, name="python-client", timeout=5.0, reconnect=False,
                 receive_buffer_bytes=32 << 20, retry_interval=RETRY_INTERVAL_S,
                 keepalive_interval=KEEPALIVE_INTERVAL_S, step_retry_s=2.0, max_frame_bytes=256 << 20):
        super().__init__(address, name, timeout, reconnect)
        self.receive_buffer_bytes = receive_buffer_bytes
        self.retry_interval = retry_interval
        self.keepalive_interval = keepalive_interval
        self.step_retry_s = step_retry_s
        self.reassembler = FrameReassembler(max_frame_bytes)
        self.malformed = 0
        self.sequence = 0  # the last Envelope.sequence sent
        self._sock = None
        self._buf = bytearray(_MAX_DATAGRAM)
        self._view = memoryview(self._buf)
        self._frames = collections.deque(maxlen=64)  # reassembled pb.Frames, oldest first
        self._replies = collections.deque(maxlen=64)  # (kind, message)
        self._last_send = 0.0
        self._last_datagram = 0.0

    # -- datagrams ---------------------------------------------------------
    def _open(self, timeout):
        try:
            self._sock = open_datagram_socket(self.address.host, self.address.port, self.receive_buffer_bytes)
        except OSError as e:
            raise ConnectionClosed("cannot open a UDP socket to sim4cvd at %s (UDP): %s" % (
                self.address, e.strerror or e)) from e
        self._frames.clear()
        self._replies.clear()
        self.reassembler = FrameReassembler(self.reassembler.max_frame_bytes)

    def _close(self):
        sock = self._sock
        if sock is not None and self._subscription is not None and self.delivery == pb.DELIVERY_LOCKSTEP:
            # UDP has no goodbye: the registration lingers for --udp-expiry-ms.
            # Leaving lockstep now keeps it from holding the simulation back.
            release = pb.Subscribe()
            release.CopyFrom(self._subscription)
            release.delivery = pb.DELIVERY_NEWEST
            try:
                self._send(envelope(subscribe=release))
            except (OSError, ConnectionClosed):
                pass
        self._sock = None
        if sock is not None:
            sock.close()

    def _refused(self, e):
        self._open_now = False
        return ConnectionClosed("sim4cvd at %s (UDP) is not there: the port is unreachable (%s)" % (
            self.address, e.strerror or e))

    def _send(self, env):
        if self._sock is None:
            raise ConnectionClosed("not connected to %s" % (self.address,))
        self.sequence += 1
        env.sequence = self.sequence
        try:
            self._sock.send(env.SerializeToString())
        except ConnectionRefusedError as e:
            raise self._refused(e) from e
        self._last_send = time.monotonic()

    def _receive_one(self, wait_s):
        """Reads one datagram (waiting up to wait_s; 0: not at all) and files
        it; False if none came."""
        sock = self._sock
        if sock is None:
            raise ConnectionClosed("not connected to %s" % (self.address,))
        if wait_s <= 0:
            sock.setblocking(False)
        else:
            sock.settimeout(wait_s)
        try:
            n = sock.recv_into(self._buf)
        except (socket.timeout, BlockingIOError, InterruptedError):
            return False
        except ConnectionRefusedError as e:
            raise self._refused(e) from e
        self._last_datagram = time.monotonic()
        env = pb.Envelope()
        try:
            env.ParseFromString(self._view[:n])
        except Exception:
            self.malformed += 1
            return True
        kind = env.WhichOneof("kind")
        if kind == "frame_chunk":
            data = self.reassembler.add(env.frame_chunk)
            if data is not None:
                whole = pb.Envelope()
                try:
                    whole.ParseFromString(data)
                except Exception:
                    self.malformed += 1
                    return True
                if whole.WhichOneof("kind") == "frame":
                    self._frames.append(whole.frame)
        elif kind == "frame":
            self._frames.append(env.frame)
        elif kind in _REPLY_KINDS:
            self._replies.append((kind, getattr(env, kind)))
        return True

    def _drain(self):
        for _ in range(_DRAIN_LIMIT):
            if not self._receive_one(0):
                break

    def _raise_errors(self, all_errors):
        for item in list(self._replies):
            kind, message = item
            if kind == "error" and (all_errors or message.fatal):
                self._replies.remove(item)
                if message.fatal:
                    self._open_now = False  # the registration is gone
                raise ServerError.from_message(message)

    def _take_reply(self, match):
        for item in self._replies:
            if match(*item):
                self._replies.remove(item)
                return item[1]
        return None

    def _wait(self, ready, timeout, resend=None, resend_interval=None, errors_interrupt=True):
        """Receives until ready() returns something, re-sending with resend()
        every resend_interval and keep-alives after silence."""
        now = time.monotonic()
        deadline = None if timeout is None else now + timeout
        interval = resend_interval or self.retry_interval
        next_resend = now + interval
        while True:
            self._raise_errors(errors_interrupt)
            result = ready()
            if result is not None:
                return result
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                raise TimeoutError("no answer from sim4cvd at %s (UDP) within %.2f s" % (self.address, timeout))
            if resend is not None and now >= next_resend:
                if resend() is not False:
                    next_resend = now + interval
            if now - self._last_send >= self.keepalive_interval:
                self._send(pb.Envelope())  # keep-alive: no message, only a sequence number
            wake = [self._last_send + self.keepalive_interval]
            if deadline is not None:
                wake.append(deadline)
            if resend is not None:
                wake.append(next_resend)
            if self._receive_one(max(0.001, min(wake) - time.monotonic())):
                self._drain()

    # -- hooks -------------------------------------------------------------
    def _exchange(self, env, kind, timeout):
        self._replies = collections.deque((item for item in self._replies if item[0] != kind), maxlen=64)
        self._send(env)
        reply = self._wait(lambda: self._take_reply(lambda k, m: k == kind), timeout, resend=lambda: self._send(env))
        if kind == "subscribed":
            self._frames.clear()  # frames of the replaced subscription
        return reply

    def _pop_frame(self):
        return Frame.from_message(self._frames.popleft()) if self._frames else None

    def _next_frame(self, timeout, copy):
        def step_again():
            quiet = time.monotonic() - self._last_datagram >= self.step_retry_s
            if (self.delivery == pb.DELIVERY_LOCKSTEP and self._steps_outstanding and quiet
                    and self.reassembler.in_progress is None):
                self._send(envelope(step=pb.Step()))  # the frame or its Step was lost
                return True
            return False
        return self._wait(self._pop_frame, timeout, resend=step_again, resend_interval=self.step_retry_s)

    def _newest_frame(self, timeout, copy):
        self._drain()
        self._frames.clear()  # older than what NextFrame brings
        request = envelope(next_frame=pb.NextFrame())
        self._send(request)
        return self._wait(self._pop_frame, timeout, resend=lambda: self._send(request))

    def _configure(self, request, request_id, timeout):
        env = pb.Envelope()
        env.configure.CopyFrom(request)
        env.configure.request_id = request_id

        def answers(kind, message):
            return kind in ("configured", "error") and message.request_id == request_id

        self._send(env)
        # Every retry carries the same request_id: the daemon answers a repeat
        # from its cache of the last 16 instead of carrying it out again.
        answer = self._wait(lambda: self._take_reply(answers), timeout, resend=lambda: self._send(env),
                            errors_interrupt=False)
        if isinstance(answer, pb.Error):
            raise ServerError.from_message(answer)
        return answer
