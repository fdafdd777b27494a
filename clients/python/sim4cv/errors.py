"""The exceptions of the sim4cv client, one hierarchy for every transport.

    Sim4cvError
    ├── ServerError        the daemon answered with an Error envelope
    ├── ConnectionClosed   (also a ConnectionError) no session: closed, refused, lost
    ├── ProtocolError      (also a ConnectionError) the peer broke the framing
    ├── ShmLayoutError     the shared memory is not the layout this client reads
    └── StaleFrameError    a zero-copy shared-memory frame was overwritten
"""

from ._proto import pb


class Sim4cvError(Exception):
    """Base class of every error this package raises (TimeoutError aside)."""


class ServerError(Sim4cvError):
    """The daemon answered with an Error envelope.

    code       -- ErrorCode value (compare with sim4cv.pb.ERROR_CODE_*)
    message    -- the server's human-readable explanation
    fatal      -- True if the server has closed the connection after sending it
    request_id -- the Configure.request_id it answers; 0 for Errors about other messages
    """

    def __init__(self, code: int, message: str, fatal: bool, request_id: int = 0):
        self.code = int(code)
        self.message = message
        self.fatal = bool(fatal)
        self.request_id = int(request_id)
        super().__init__("%s%s: %s" % (self.code_name, " (fatal)" if self.fatal else "", message))

    @property
    def code_name(self) -> str:
        try:
            return pb.ErrorCode.Name(self.code)
        except ValueError:
            return "ERROR_CODE_%d" % self.code

    @classmethod
    def from_message(cls, error: "pb.Error") -> "ServerError":
        return cls(error.code, error.message, error.fatal, error.request_id)


class ConnectionClosed(Sim4cvError, ConnectionError):
    """The connection is closed (by the peer, by a fatal error, or by
    close()), or could not be made; the message names the address."""


class ProtocolError(Sim4cvError, ConnectionError):
    """The peer broke the framing (oversized prefix, unparsable bytes, or an
    envelope of a kind the server never sends). The connection is closed."""


class ShmLayoutError(Sim4cvError):
    """The shared memory is not what this client reads: another layout
    version (the message names both), a bad magic, or geometry that does not
    add up."""


class StaleFrameError(Sim4cvError):
    """The daemon has begun overwriting the ring slot of a zero-copy frame:
    its pixels no longer belong to that frame."""
