"""TCP framing (docs/protocol.md section 2): every Envelope is preceded by
its serialized size as a 4-byte little-endian unsigned integer."""

import socket
import struct
import time

from ._proto import pb
from .errors import ConnectionClosed, ProtocolError

PROTOCOL_VERSION = 1
LENGTH_PREFIX_BYTES = 4
DEFAULT_MAX_MESSAGE_BYTES = 64 << 20  # what we accept from the daemon: frames can be tens of MB

_PREFIX = struct.Struct("<I")


def encode_length_prefix(size: int) -> bytes:
    """The 4-byte little-endian prefix for a message of `size` bytes."""
    return _PREFIX.pack(size)


def decode_length_prefix(data) -> int:
    """The size encoded in the first 4 bytes of `data` (any bytes-like object)."""
    return _PREFIX.unpack_from(data)[0]


def encode_envelope(envelope: "pb.Envelope") -> bytes:
    """Prefix + serialized bytes of `envelope`, ready to write to the stream."""
    payload = envelope.SerializeToString()
    return _PREFIX.pack(len(payload)) + payload


def decode_envelope(payload) -> "pb.Envelope":
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
        try:
            self.sock.sendall(data)
        except (BrokenPipeError, ConnectionResetError) as e:
            raise ConnectionClosed("the server closed the connection (%s)" % e) from e

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
