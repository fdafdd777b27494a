"""Enum helpers (names such as "rgb" or "lockstep" for proto enum values) and
numpy views of pixel planes, shared by every transport."""

import numpy as np

from ._proto import pb


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


_CHANNEL_VALUES = {}  # name -> value, filled as names are asked for: a frame loop asks for the same few


def channel_value(channel) -> int:
    """CHANNEL_* value for an int or a name such as "rgb", "DEPTH", "CHANNEL_MASK"."""
    if isinstance(channel, str):
        value = _CHANNEL_VALUES.get(channel)
        if value is None:
            value = _CHANNEL_VALUES[channel] = _enum_value(pb.Channel, "CHANNEL_", channel)
        return value
    return int(channel)


def delivery_value(delivery) -> int:
    """DELIVERY_* value for an int or a name such as "lockstep", "newest" or "on_request"."""
    return _enum_value(pb.Delivery, "DELIVERY_", delivery)


def entity_kind_value(kind) -> int:
    """ENTITY_KIND_* value for an int or a name such as "car" or "uav"."""
    return _enum_value(pb.EntityKind, "ENTITY_KIND_", kind)


def channel_name(channel) -> str:
    """"CHANNEL_RGB" for 1 (or the number if the enum does not know it)."""
    try:
        return pb.Channel.Name(channel_value(channel))
    except ValueError:
        return "CHANNEL_%d" % channel_value(channel)


# ElementType -> numpy dtype. Each image (a protobuf Image or a shared-memory
# channel record) says its element type and components, so any channel,
# including ones added after this client, can be viewed without a table.
ELEMENT_DTYPES = {
    pb.ELEMENT_TYPE_U8: np.dtype(np.uint8),
    pb.ELEMENT_TYPE_U16: np.dtype("<u2"),
    pb.ELEMENT_TYPE_F32: np.dtype("<f4"),
}


def plane_view(buffer, offset, width, height, stride, element, components, what="image"):
    """A numpy array over `buffer` (no copy) of `height` rows `stride` bytes
    apart, starting at byte `offset`: (h, w) for one component, else
    (h, w, components). Read-only if the buffer is. Raises ValueError if the
    element type is unknown or the buffer is too short."""
    try:
        dtype = ELEMENT_DTYPES[element]
    except KeyError:
        raise ValueError("%s: unsupported element type %d" % (what, element)) from None
    if components < 1:
        raise ValueError("%s has %d components" % (what, components))
    row_bytes = width * components * dtype.itemsize
    available = len(memoryview(buffer).cast("B")) - offset
    if stride < row_bytes or (height and available < (height - 1) * stride + row_bytes):
        raise ValueError("%s: %d bytes with stride %d do not hold %dx%d pixels" % (
            what, available, stride, width, height))
    if components == 1:
        shape, strides = (height, width), (stride, dtype.itemsize)
    else:
        shape, strides = (height, width, components), (stride, components * dtype.itemsize, dtype.itemsize)
    return np.ndarray(shape, dtype=dtype, buffer=buffer, offset=offset, strides=strides)


def find_image(frame, channel):
    """The Image of `channel` in `frame` (a pb.Frame), or None if the frame does not carry it."""
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

    `frame` is a pb.Frame or a sim4cv.Frame. The array wraps the received
    bytes without copying (honouring the row stride), so it is read-only;
    call .copy() to get a writable array. Raises KeyError if the frame does
    not carry the channel.
    """
    if not isinstance(frame, pb.Frame):
        return frame.image(channel)
    image = find_image(frame, channel)
    if image is None:
        raise KeyError("frame %d does not carry channel %s" % (frame.frame_id, channel_name(channel)))
    data = image.data  # one bytes object; the array below keeps it alive
    return plane_view(data, 0, frame.width, frame.height, image.stride, image.element, image.components,
                      "image of channel %s" % channel_name(image.channel))
