"""The common client API over TCP (docs/protocol.md sections 2-11), built on
the protobuf-level sim4cv.Client."""

import socket

from .base import BaseClient
from .client import Client
from .errors import ConnectionClosed
from .frame import Frame
from ._proto import pb


class TcpClient(BaseClient):
    """sim4cv.connect("tcp://HOST:PORT"): one TCP connection (TCP_NODELAY).
    .raw is the underlying sim4cv.Client (protobuf messages)."""

    transport = "tcp"

    def __init__(self, address, name="python-client", timeout=5.0, reconnect=False, max_message_bytes=64 << 20):
        super().__init__(address, name, timeout, reconnect)
        self.raw = Client(max_message_bytes)

    def _open(self, timeout):
        try:
            self.raw.connect_raw(self.address.host, self.address.port, timeout)
        except (OSError, socket.timeout) as e:
            raise ConnectionClosed("cannot connect to sim4cvd at %s (TCP): %s" % (
                self.address, e.strerror or e)) from e

    def _close(self):
        self.raw.close()

    def _send(self, env):
        self.raw.send_envelope(env)

    def _exchange(self, env, kind, timeout):
        raw = self.raw
        raw.send_envelope(env)
        if kind == "subscribed":
            raw._drop_queued_frames()
        reply = raw._receive_kind(kind, timeout)
        if kind == "subscribed":
            raw._drop_queued_frames()  # frames read before Subscribed belong to the old subscription
        return reply

    def _next_frame(self, timeout, copy):
        return Frame.from_message(self.raw.receive_frame(timeout))

    def _newest_frame(self, timeout, copy):
        self.raw._drop_queued_frames()  # older than what NextFrame brings
        return Frame.from_message(self.raw.request_frame(timeout))

    def _configure(self, request, request_id, timeout):
        self.raw._last_request_id = request_id - 1  # the raw client numbers it: keep one sequence
        return self.raw.configure(request, timeout)
