"""Python client for the sim4cv simulator daemon (sim4cvd).

See docs/python.md for a guide and docs/protocol.md for the wire protocol.
`pb` is the protobuf module generated from protocol/sim4cv.proto; every enum
value is also re-exported here (sim4cv.CHANNEL_RGB, sim4cv.ERROR_CODE_..., ...).
"""

from ._proto import pb
from .client import (
    DEFAULT_MAX_MESSAGE_BYTES,
    PROTOCOL_VERSION,
    Client,
    ConnectionClosed,
    FramedSocket,
    ProtocolError,
    ServerError,
    channel_value,
    decode_envelope,
    decode_length_prefix,
    delivery_value,
    encode_envelope,
    entity_kind_value,
    encode_length_prefix,
    find_image,
    image_array,
)
from . import visualize

# Re-export enum values (CHANNEL_RGB, DELIVERY_LOCKSTEP, ERROR_CODE_UNKNOWN_CAMERA, ...).
for _enum in pb.DESCRIPTOR.enum_types_by_name.values():
    for _value in _enum.values:
        globals()[_value.name] = _value.number
del _enum, _value

__all__ = [
    "pb", "Client", "ServerError", "ConnectionClosed", "ProtocolError", "FramedSocket",
    "image_array", "find_image", "channel_value", "delivery_value", "entity_kind_value",
    "encode_envelope", "decode_envelope", "encode_length_prefix", "decode_length_prefix",
    "PROTOCOL_VERSION", "DEFAULT_MAX_MESSAGE_BYTES", "visualize",
]
