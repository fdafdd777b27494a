"""The byte layout of sim4cvd's shared memory, layout version 4
(protocol/shm_layout.h, docs/protocol.md section 13), and the futex call.

Every address the client uses comes from the geometry parse_ring_header()
validates and returns, never from fields read again later.
"""

import ctypes
import ctypes.util
import struct
from typing import Dict, NamedTuple

from . import channel_table
from ._proto import pb
from .errors import ShmLayoutError

LAYOUT_VERSION = 4
MAGIC = b"SIM4CVSM"
AREA_MAGIC = b"SIM4CVCA"
ATTACH_MAGIC = b"SIM4CVAT"
SOCKET_PREFIX = "sim4cv-shm"
HEADER_BYTES = 512
FRAME_HEADER_BYTES = 8192
SLOTS_OFFSET = 4096
ALIGNMENT = 64
MAX_CHANNELS = 8
MAX_BOXES = 128
MAX_ENTITIES = 8
ATTACH_BYTES = 256

# The channel table (protocol/channels.h, copied by tools/channel_tables.py):
# pixel channels in plane order, bytes per pixel.
PIXEL_CHANNELS = tuple((pb.Channel.Value(channel), bytes_per_pixel)
                       for _, channel, _, _, _, bytes_per_pixel, _ in channel_table.PIXEL_CHANNELS)
ALL_PIXELS_MASK = sum(1 << c for c, _ in PIXEL_CHANNELS)

# Frame object header offsets.
OFF_PUBLISHED, OFF_NEWEST_FRAME_ID, OFF_FRAME_FUTEX, OFF_CLOSED = 192, 200, 208, 216
# Frame slot header: sequence .. camera_index (72 bytes), channel records, boxes, entities.
SLOT_HEAD = struct.Struct("<QQQdqIIIIIIII")
CHANNEL_RECORD = struct.Struct("<IIIHBBQQ")
OFF_CHANNELS, OFF_BOXES, OFF_ENTITIES = 128, 384, 4480
BOX = struct.Struct("<IIIIIIfI")
ENTITY = struct.Struct("<II3d4d3d3d")

# A client's area (13.5).
AREA_HEADER_BYTES = 256
REQUEST_OFFSET = 256
REQUEST_CAPACITY = 64
REQUEST_SLOT_BYTES = 256
REQUEST_DATA_BYTES = 248
RESPONSE_OFFSET = REQUEST_OFFSET + REQUEST_CAPACITY * REQUEST_SLOT_BYTES  # 16640
RESPONSE_DEPTH = 8
RESPONSE_MESSAGE_BYTES = 2048
RESPONSE_DATA_OFFSET = 64
RESPONSE_DATA_BYTES = 1984
# A response message's on_socket word: 1 when its Envelope (`size` bytes) is
# the next socket message, after an 8-byte response number; at most this long.
OFF_RESPONSE_ON_SOCKET = 12
SOCKET_RESPONSE_HEADER_BYTES = 8
SOCKET_RESPONSE_BYTES = 131072
AREA_BYTES = (RESPONSE_OFFSET + RESPONSE_DEPTH * RESPONSE_MESSAGE_BYTES + 4095) // 4096 * 4096  # 36864
OFF_REQUEST_WRITE, OFF_REQUEST_READ, OFF_RESPONSES_WRITTEN = 64, 128, 136
OFF_RESPONSE_FUTEX, OFF_AREA_CLOSED = 144, 148

_RING_HEAD = struct.Struct("<8sIIQIIQQIIII32s")  # magic .. camera_name (96 bytes)
_AREA_HEAD = struct.Struct("<8sIIQQIIQII")
_ATTACH = struct.Struct("<8sIIQQ224s")


def align_up(value: int, alignment: int) -> int:
    return (value + alignment - 1) // alignment * alignment


def socket_address(name: str) -> str:
    """The abstract Unix socket address of --shm-name NAME ("/NAME")."""
    return "\0" + SOCKET_PREFIX + name


class RingGeometry(NamedTuple):
    """What the client keeps of the frame object's header, validated."""
    slot_count: int
    slot_bytes: int
    slots_offset: int
    total_bytes: int
    width: int
    height: int
    channel_mask: int
    plane_offsets: Dict[int, int]  # channel -> offset within a slot
    camera_name: str
    expiry_ms: int
    protocol_version: int
    writer_pid: int


def compute_geometry(width, height, slot_count, channel_mask):
    """(plane offsets, slot_bytes, total_bytes) as docs/protocol.md 13.2 computes them."""
    pixels = width * height
    end, offsets = FRAME_HEADER_BYTES, {}
    for channel, bytes_per_pixel in PIXEL_CHANNELS:
        if channel_mask & (1 << channel):
            offsets[channel] = align_up(end, ALIGNMENT)
            end = offsets[channel] + pixels * bytes_per_pixel
    slot_bytes = align_up(end, 4096)
    return offsets, slot_bytes, SLOTS_OFFSET + slot_bytes * slot_count


def check_layout_version(version: int, what: str) -> None:
    if version != LAYOUT_VERSION:
        raise ShmLayoutError("%s has shared-memory layout version %d but this client reads layout version %d; "
                             "use a client made for layout version %d" % (what, version, LAYOUT_VERSION, version))


def parse_ring_header(buf, object_bytes: int = None, what: str = "the shared-memory ring") -> RingGeometry:
    """Checks the frame object's header (any bytes-like object holding at
    least its first 512 bytes) in the order of docs/protocol.md 13.1 and
    returns its geometry; ShmLayoutError saying what is wrong otherwise
    (for another layout version, naming both versions)."""
    size = len(buf) if object_bytes is None else object_bytes
    if len(buf) < HEADER_BYTES or size < HEADER_BYTES:
        raise ShmLayoutError("%s is %d bytes, shorter than its %d-byte header" % (what, size, HEADER_BYTES))
    (magic, version, header_bytes, total, slot_count, frame_header_bytes, slot_bytes, slots_offset,
     width, height, writer_pid, max_boxes, camera) = _RING_HEAD.unpack_from(buf, 0)
    if magic != MAGIC:
        raise ShmLayoutError("%s does not start with %r (found %r): not a sim4cvd frame object" % (what, MAGIC, magic))
    check_layout_version(version, what)
    if header_bytes != HEADER_BYTES or frame_header_bytes != FRAME_HEADER_BYTES or max_boxes != MAX_BOXES:
        raise ShmLayoutError("%s: header sizes %d/%d/%d differ from layout version %d" % (
            what, header_bytes, frame_header_bytes, max_boxes, LAYOUT_VERSION))
    max_entities, expiry_ms, protocol_version = struct.unpack_from("<III", buf, 132)
    channel_mask = struct.unpack_from("<I", buf, 152)[0]
    if channel_mask == 0 or channel_mask & ~ALL_PIXELS_MASK:
        raise ShmLayoutError("%s: channel_mask 0x%x is not a set of pixel channels" % (what, channel_mask))
    if slot_count < 2 or max_entities != MAX_ENTITIES:
        raise ShmLayoutError("%s: slot_count %d / max_entities %d are invalid" % (what, slot_count, max_entities))
    offsets, want_slot_bytes, want_total = compute_geometry(width, height, slot_count, channel_mask)
    if (slot_bytes, slots_offset, total) != (want_slot_bytes, SLOTS_OFFSET, want_total) or total > size:
        raise ShmLayoutError("%s: slot_bytes %d, slots_offset %d, total_bytes %d do not match %dx%d, %d slots "
                             "(expected %d, %d, %d in an object of %d bytes)" % (
                                 what, slot_bytes, slots_offset, total, width, height, slot_count,
                                 want_slot_bytes, SLOTS_OFFSET, want_total, size))
    name = camera.split(b"\0", 1)[0].decode("utf-8", "replace")
    return RingGeometry(slot_count, slot_bytes, SLOTS_OFFSET, total, width, height, channel_mask, offsets, name,
                        expiry_ms, protocol_version, writer_pid)


def check_area_header(buf, what="the shared-memory client area"):
    """Checks a client's area header against the constants of 13.5."""
    (magic, version, header_bytes, total, request_offset, capacity, slot_bytes, response_offset, depth,
     message_bytes) = _AREA_HEAD.unpack_from(buf, 0)
    if magic != AREA_MAGIC:
        raise ShmLayoutError("%s does not start with %r (found %r)" % (what, AREA_MAGIC, magic))
    check_layout_version(version, what)
    if (header_bytes, total, request_offset, capacity, slot_bytes, response_offset, depth, message_bytes) != (
            AREA_HEADER_BYTES, AREA_BYTES, REQUEST_OFFSET, REQUEST_CAPACITY, REQUEST_SLOT_BYTES,
            RESPONSE_OFFSET, RESPONSE_DEPTH, RESPONSE_MESSAGE_BYTES):
        raise ShmLayoutError("%s: its geometry differs from layout version %d" % (what, LAYOUT_VERSION))


def parse_attach(message: bytes, what: str):
    """(status, frames_bytes, area_bytes, reason) of the daemon's attach message."""
    if len(message) < ATTACH_BYTES:
        raise ShmLayoutError("%s: the attach message is %d bytes, expected %d" % (what, len(message), ATTACH_BYTES))
    magic, version, status, frames_bytes, area_bytes, reason = _ATTACH.unpack_from(message, 0)
    if magic != ATTACH_MAGIC:
        raise ShmLayoutError("%s: the attach message starts with %r, expected %r" % (what, magic, ATTACH_MAGIC))
    check_layout_version(version, what)
    return status, frames_bytes, area_bytes, reason.split(b"\0", 1)[0].decode("utf-8", "replace")


# -- futex ------------------------------------------------------------------

SYS_FUTEX = 202  # x86-64
FUTEX_WAIT = 0


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


_libc = None


def _syscall():
    global _libc
    if _libc is None:
        _libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        _libc.syscall.restype = ctypes.c_long
    return _libc.syscall


def futex_wait(address: int, expected: int, timeout_s: float) -> None:
    """FUTEX_WAIT (shared, not private) on the u32 at `address` while it
    equals `expected`, for at most timeout_s. Returns on wake-up, mismatch,
    signal or timeout; callers re-check their condition. Needs x86-64 Linux
    (SYS_futex 202); callers fall back to sleeping elsewhere."""
    seconds = max(0.0, timeout_s)
    ts = _Timespec(int(seconds), int((seconds - int(seconds)) * 1e9))
    _syscall()(ctypes.c_long(SYS_FUTEX), ctypes.c_void_p(address), ctypes.c_int(FUTEX_WAIT),
               ctypes.c_uint(expected & 0xFFFFFFFF), ctypes.byref(ts), None, ctypes.c_int(0))
