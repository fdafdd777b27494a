"""TraX messages as pure functions: parse and format lines, encode images,
parse and format regions. No processes, no I/O (see sim4cv.trax for that).

Written from the TraX protocol specification (votchallenge/trax,
docs/protocol.rst); where the specification is silent the behaviour of the
reference C library (src/message.c, src/trax.c, src/region.c) is followed,
and such places say so. See docs/trax.md.

    >>> format_message("state", ["10.0000,20.0000,30.0000,40.0000"], {"note": "a b"})
    '@@TRAX:state "10.0000,20.0000,30.0000,40.0000" "note=a b"\\n'
    >>> parse_message('@@TRAX:hello trax.version=3 "trax.name=my tracker"')
    Message(name='hello', arguments=[], properties={'trax.version': '3', 'trax.name': 'my tracker'})
"""

import base64
import math
import re
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

PREFIX = "@@TRAX:"
# Message names of the specification ("Protocol messages and states"), and
# "status", which the reference library reads as "state". "error" is not in
# the specification: sim4cv reads it from a tracker as a failure report.
MESSAGE_NAMES = ("hello", "initialize", "frame", "state", "quit")
ALIASES = {"status": "state"}
NONSTANDARD_NAMES = ("error",)
MAX_KEY_LENGTH = 64                     # "Named arguments": at most 64 characters
_KEY = re.compile(r"^[A-Za-z0-9._]{1,%d}$" % MAX_KEY_LENGTH)

# The versions sim4cv speaks: 1 (the original), 2 (trax.channels), 3 (mask
# regions), 4 (multi-object: initialize carries only the region, the image
# follows in a frame message).
MIN_VERSION, MAX_VERSION = 1, 4
# Image formats ("Image formats"; "buffer" is the name the reference library
# announces for the specification's "data" URIs) and region formats.
IMAGE_FORMATS = ("memory", "buffer", "path")          # sim4cv's order of preference
REGION_FORMATS = ("rectangle", "polygon")             # rectangle preferred


class MessageError(ValueError):
    """A line that is not a well-formed TraX message (the message says why)."""


class Message(NamedTuple):
    name: str                       # lowercase: hello, initialize, frame, state, quit (or error)
    arguments: List[str]            # the mandatory arguments, in order, unescaped
    properties: Dict[str, str]      # the named (key=value) arguments


def is_valid_key(key: str) -> bool:
    """A property key: 1 to 64 characters of letters, digits, '.' and '_'."""
    return bool(_KEY.match(key))


def escape(text: str) -> str:
    """The specification's escape sequences: \\" for ", \\\\ for \\, \\n for a newline."""
    return text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")


def format_message(name: str, arguments: Sequence[str] = (), properties: Optional[Dict[str, str]] = None) -> str:
    """One message line, newline included. Every argument and every key=value
    pair is written in double quotes with its value escaped, so spaces,
    commas, quotes, backslashes and newlines survive. ValueError for a bad
    name or key, or an argument that a reader would take for a key=value pair."""
    if not re.match(r"^[A-Za-z0-9]+$", name):
        raise ValueError("bad TraX message name %r" % (name,))
    parts = [PREFIX + name]
    for arg in arguments:
        arg = str(arg)
        head, eq, _ = arg.partition("=")
        if eq and is_valid_key(head):
            raise ValueError("TraX argument %r would be read as the named argument %r" % (arg, head))
        parts.append('"%s"' % escape(arg))
    for key, value in (properties or {}).items():
        if not is_valid_key(key):
            raise ValueError("bad TraX property key %r: 1-%d letters, digits, '.' or '_'"
                             % (key, MAX_KEY_LENGTH))
        parts.append('"%s=%s"' % (key, escape(str(value))))
    return " ".join(parts) + "\n"


def is_message_line(line: str) -> bool:
    """True if the line is meant for the protocol (starts with @@TRAX:);
    every other line is the tracker's own output, which the protocol ignores."""
    return line.startswith(PREFIX)


_QUOTED = re.compile(r'"([^"\\]*(?:\\.[^"\\]*)*)"', re.S)
_UNQUOTED = re.compile(r'([^ \\]*(?:\\.[^ \\]*)*)', re.S)
_KEY_PREFIX = re.compile(r"([A-Za-z0-9._]{1,%d})=" % MAX_KEY_LENGTH)
_ESCAPE = re.compile(r"\\(.)", re.S)


def unescape(text: str) -> str:
    """Inverse of escape(): \\n is a newline, \\X is X (as the reference library)."""
    if "\\" not in text:
        return text
    return _ESCAPE.sub(lambda m: "\n" if m.group(1) == "n" else m.group(1), text)


def _split_tokens(body: str, line: str) -> List[Tuple[str, Optional[str]]]:
    """Tokens of a message body as (text, value): value is None for an
    argument, else text is the key of a named argument. Tokens are separated
    by spaces; a token is "quoted" (spaces allowed) or bare, with escapes in
    both. Only the first '=' can split a token, and only where the text before
    it is a valid key (so the '=' of Base64 padding stays in its argument)."""
    tokens = []
    pos, n = 0, len(body)
    while pos < n:
        if body[pos] == " ":
            pos += 1
            continue
        if body[pos] == '"':
            m = _QUOTED.match(body, pos)
            if not m:
                raise MessageError("TraX message has an unterminated quoted argument: %r" % line)
            if m.end() < n and body[m.end()] != " ":
                raise MessageError("TraX message has no space after a quoted argument: %r" % line)
        else:
            m = _UNQUOTED.match(body, pos)
            if m.end() < n and body[m.end()] != " ":
                raise MessageError("TraX message ends inside an escape sequence: %r" % line)
        raw, pos = m.group(1), m.end()
        k = _KEY_PREFIX.match(raw)
        tokens.append((k.group(1), unescape(raw[k.end():])) if k else (unescape(raw), None))
    return tokens


def parse_message(line: str) -> Message:
    """Parses one line (a trailing newline or carriage return is dropped).
    MessageError if it is not a TraX line, names an unknown message, or
    breaks the quoting rules."""
    line = line.rstrip("\n").rstrip("\r")
    if not is_message_line(line):
        raise MessageError("not a TraX message (no %s prefix): %r" % (PREFIX, line))
    rest = line[len(PREFIX):]
    m = re.match(r"^([A-Za-z0-9]*)(.*)$", rest, re.S)
    name, body = m.group(1).lower(), m.group(2)
    if body and body[0] != " ":
        raise MessageError("TraX message name is not followed by a space: %r" % line)
    name = ALIASES.get(name, name)
    if name not in MESSAGE_NAMES and name not in NONSTANDARD_NAMES:
        raise MessageError("unknown TraX message %r: %r" % (name, line))
    arguments, properties = [], {}
    for text, value in _split_tokens(body, line):
        if value is None:
            arguments.append(text)
        else:
            properties[text] = value
    return Message(name, arguments, properties)


def split_list(value: Optional[str]) -> List[str]:
    """A hello list ("path;memory;" as the reference library writes it, or
    comma- or space-separated): the names in order, empty ones dropped."""
    return [v for v in re.split(r"[;, ]+", value or "") if v]


# --- images -----------------------------------------------------------------

def encode_memory_image(image: np.ndarray) -> str:
    """The "memory" format: "image:WIDTH;HEIGHT;FORMAT;" then the raw pixels,
    row after row, in Base64. FORMAT: rgb (HxWx3 uint8, R G B per pixel),
    gray8 (HxW uint8) or gray16 (HxW uint16; little-endian, the reference
    library's in-memory order on every machine it runs on)."""
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8:
        fmt = "rgb"
    elif image.ndim == 2 and image.dtype == np.uint8:
        fmt = "gray8"
    elif image.ndim == 2 and image.dtype == np.uint16:
        fmt = "gray16"
        image = image.astype("<u2", copy=False)
    else:
        raise ValueError("TraX memory images are HxWx3 uint8 (rgb), HxW uint8 (gray8) or HxW uint16 "
                         "(gray16), not %s %s" % (image.shape, image.dtype))
    h, w = image.shape[:2]
    data = base64.b64encode(np.ascontiguousarray(image).tobytes()).decode("ascii")
    return "image:%d;%d;%s;%s" % (w, h, fmt, data)


def decode_memory_image(text: str) -> np.ndarray:
    """Inverse of encode_memory_image: HxWx3 uint8 for rgb, HxW for gray8/16."""
    if not text.startswith("image:"):
        raise ValueError("not a TraX memory image (no image: prefix)")
    try:
        w, h, fmt, data = text[len("image:"):].split(";", 3)
        w, h = int(w), int(h)
    except ValueError:
        raise ValueError("bad TraX memory image header %r" % text[:60]) from None
    shapes = {"rgb": ((h, w, 3), np.uint8), "gray8": ((h, w), np.uint8), "gray16": ((h, w), np.dtype("<u2"))}
    if fmt not in shapes or w < 1 or h < 1:
        raise ValueError("bad TraX memory image header %r" % text[:60])
    shape, dtype = shapes[fmt]
    raw = base64.b64decode(data, validate=True)
    if len(raw) != int(np.prod(shape)) * np.dtype(dtype).itemsize:
        raise ValueError("TraX memory image %dx%d %s has %d bytes" % (w, h, fmt, len(raw)))
    return np.frombuffer(raw, dtype=dtype).reshape(shape)


def encode_buffer_image(encoded: bytes, mime: str = "image/png") -> str:
    """The "buffer" format (the specification's "data" URI): "data:MIME;"
    then the PNG or JPEG file in Base64, as the reference library writes it."""
    return "data:%s;%s" % (mime, base64.b64encode(encoded).decode("ascii"))


def encode_path_image(path: str) -> str:
    """The "path" format: a file:// URL of an absolute path to a JPEG or PNG."""
    return "file://" + path


# --- regions ----------------------------------------------------------------

class Region(NamedTuple):
    kind: str                       # "rectangle", "polygon", "mask" or "special"
    values: Tuple[float, ...]       # rectangle: x,y,w,h; polygon: x1,y1,...; special: (code,)

    def bounding_box(self) -> Optional[Tuple[float, float, float, float]]:
        """(x, y, w, h): the rectangle, or the axis-aligned box around a
        polygon; None for a special region (the tracker gives no box)."""
        if self.kind == "rectangle":
            return tuple(self.values)
        if self.kind == "polygon":
            xs, ys = self.values[0::2], self.values[1::2]
            return (min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys))
        if self.kind == "special":
            return None
        raise ValueError("no box for a %s region" % self.kind)


def format_rectangle(box: Sequence[float]) -> str:
    """"x,y,w,h" (left, top, width, height), four decimals as the reference library."""
    x, y, w, h = (float(v) for v in box)
    return "%.4f,%.4f,%.4f,%.4f" % (x, y, w, h)


def format_polygon_of_box(box: Sequence[float]) -> str:
    """The four corners of a box as a polygon "x1,y1,...,x4,y4" (clockwise from top-left)."""
    x, y, w, h = (float(v) for v in box)
    return ",".join("%.4f" % v for v in (x, y, x + w, y, x + w, y + h, x, y + h))


def parse_region(text: str) -> Region:
    """A region as written by a tracker: comma-separated numbers, with an
    optional scheme ("rect:", "poly:", "mask:", "special:"). One number is a
    special region, four a rectangle, an even number >= 6 a polygon; a value
    that is NaN makes a special region (both as the reference library).
    ValueError for anything else."""
    text = text.strip()
    kind = None
    m = re.match(r"^([a-z]+):(.*)$", text, re.S)
    if m:
        schemes = {"rect": "rectangle", "rectangle": "rectangle", "poly": "polygon", "polygon": "polygon",
                   "mask": "mask", "special": "special"}
        if m.group(1) not in schemes:
            raise ValueError("unknown region scheme %r in %r" % (m.group(1), text))
        kind, text = schemes[m.group(1)], m.group(2)
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise ValueError("region %r is not a comma-separated list of numbers" % text) from None
    if kind == "mask":
        return Region("mask", values)
    if any(math.isnan(v) for v in values):
        return Region("special", (0.0,))
    if kind is None:
        kind = {1: "special", 4: "rectangle"}.get(len(values))
        if kind is None and len(values) >= 6 and len(values) % 2 == 0:
            kind = "polygon"
    ok = {"special": len(values) == 1, "rectangle": len(values) == 4,
          "polygon": len(values) >= 6 and len(values) % 2 == 0}.get(kind, False)
    if not ok:
        raise ValueError("region %r has %d values: not a rectangle (4), polygon (even, >= 6) "
                         "or special region (1)" % (text, len(values)))
    return Region(kind, values)
