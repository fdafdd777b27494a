"""Python client for the sim4cv simulator daemon (sim4cvd).

    import sim4cv
    with sim4cv.connect("tcp://127.0.0.1:5000", name="tracker") as c:   # or udp://..., shm://NAME
        c.subscribe("uav", ["rgb", "boxes"], "lockstep")
        for frame in c.frames(count=100):
            rgb = frame.image("rgb")                       # (h, w, 3) uint8 numpy

See docs/python.md for a guide and docs/protocol.md for the wire protocol.
`pb` is the protobuf module generated from protocol/sim4cv.proto; every enum
value is also re-exported here (sim4cv.CHANNEL_RGB, sim4cv.ERROR_CODE_..., ...).
"""

from ._proto import pb
from .address import ACCEPTED_FORMS, Address, parse_address
from .base import BaseClient
from .client import Client
from .errors import (ConnectionClosed, ProtocolError, ServerError, ShmLayoutError, Sim4cvError,
                     StaleFrameError)
from .frame import Box, EntityPose, Frame
from .framing import (DEFAULT_MAX_MESSAGE_BYTES, PROTOCOL_VERSION, FramedSocket, decode_envelope,
                      decode_length_prefix, encode_envelope, encode_length_prefix)
from .images import channel_value, delivery_value, entity_kind_value, find_image, image_array
from .shm import ShmClient, ShmFrame
from .tcp import TcpClient
from .udp import UdpClient
from . import visualize

_CLIENTS = {"tcp": TcpClient, "udp": UdpClient, "shm": ShmClient}


def connect(address: str, name: str = "python-client", timeout: float = 5.0, reconnect: bool = False,
            token: str = None, **options) -> BaseClient:
    """Connects to sim4cvd and says Hello; returns a TcpClient, UdpClient or
    ShmClient (one API, see BaseClient) whose .welcome is the Welcome.

    address: "tcp://HOST:PORT", "udp://HOST:PORT" or "shm://NAME" (NAME as
    given to --shm-name, with or without its leading slash). A bad address
    raises ValueError; a daemon that is not there raises ConnectionClosed
    naming the address and transport within `timeout` seconds. reconnect:
    re-establish the session (Hello, last Subscribe) when it is lost.
    options go to the transport's class (e.g. receive_buffer_bytes for UDP).
    token: the daemon's access token (docs/security.md); by default
    SIM4CV_TOKEN, or for a local address the file the daemon wrote for it.
    """
    parsed = parse_address(address)
    client = _CLIENTS[parsed.transport](parsed, name=name, timeout=timeout, reconnect=reconnect, **options)
    client.token = token
    try:
        client.hello()
    except BaseException:
        client.close()
        raise
    return client


# Re-export enum values (CHANNEL_RGB, DELIVERY_LOCKSTEP, ERROR_CODE_UNKNOWN_CAMERA, ...).
for _enum in pb.DESCRIPTOR.enum_types_by_name.values():
    for _value in _enum.values:
        globals()[_value.name] = _value.number
del _enum, _value

__all__ = [
    "pb", "connect", "parse_address", "Address", "ACCEPTED_FORMS",
    "BaseClient", "TcpClient", "UdpClient", "ShmClient", "Frame", "ShmFrame", "Box", "EntityPose",
    "Client", "Sim4cvError", "ServerError", "ConnectionClosed", "ProtocolError", "ShmLayoutError",
    "StaleFrameError", "FramedSocket",
    "image_array", "find_image", "channel_value", "delivery_value", "entity_kind_value",
    "encode_envelope", "decode_envelope", "encode_length_prefix", "decode_length_prefix",
    "PROTOCOL_VERSION", "DEFAULT_MAX_MESSAGE_BYTES", "visualize",
]
