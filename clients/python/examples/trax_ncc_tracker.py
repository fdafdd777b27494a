#!/usr/bin/python3
"""A TraX tracker (a TraX "server"): normalised cross-correlation template
matching, written from the TraX protocol specification alone; it needs only
numpy and cv2 (Debian's python3-opencv), not sim4cv and not the TraX library.

    /usr/bin/python3 clients/python/examples/trax_ncc_tracker.py [--image-formats memory,path] [--trax-version 3]

sim4cv drives it as the tracker "trax:/usr/bin/python3 clients/python/examples/trax_ncc_tracker.py";
any TraX client (the VOT toolkit, traxclient) can drive it too. It talks
over stdin/stdout, or over TCP when TRAX_SOCKET=PORT is set (it connects to
127.0.0.1:PORT). Announces region "rectangle" (reads polygons too) and image
formats "path" and "memory" (and "buffer" if asked).

It doubles as the reference for wrapping an existing tracker: keep the
protocol part (everything above "The tracker"), replace NCCTracker by a class
with init(image, box) and update(image) -> box. See docs/trax.md.
"""

import argparse
import base64
import os
import re
import socket
import sys
import time

import cv2
import numpy as np

# --- The protocol (TraX docs/protocol.rst: "Message format", "Escape sequences",
# --- "Named arguments", "Protocol messages and states", "Image formats", "Region formats")

PREFIX = "@@TRAX:"


def escape(text):
    return text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")


def format_message(name, arguments=(), properties=None):
    """@@TRAX:name "arg" ... "key=value" ... with every part quoted and escaped."""
    parts = [PREFIX + name] + ['"%s"' % escape(a) for a in arguments]
    parts += ['"%s=%s"' % (k, escape(str(v))) for k, v in (properties or {}).items()]
    return " ".join(parts) + "\n"


TOKEN = re.compile(r' *(?:"([^"\\]*(?:\\.[^"\\]*)*)"(?= |$)|((?:[^ "\\]|\\.)[^ \\]*(?:\\.[^ \\]*)*))', re.S)
NAMED = re.compile(r"([A-Za-z0-9._]{1,64})=(.*)", re.S)


def unescape(text):
    return re.sub(r"\\(.)", lambda m: "\n" if m.group(1) == "n" else m.group(1), text, flags=re.S)


def parse_message(line):
    """(name, arguments, properties) of a @@TRAX: line; None for any other line
    (the protocol ignores them); ValueError for a broken message. Arguments
    are separated by spaces, "quoted" if they hold spaces, with the escapes
    \\" \\\\ and \\n; one that starts with key= (letters, digits, '.', '_')
    is a named argument."""
    line = line.rstrip("\r\n")
    if not line.startswith(PREFIX):
        return None
    name, _, body = line[len(PREFIX):].partition(" ")
    arguments, properties, pos = [], {}, 0
    while body[pos:].strip(" "):
        m = TOKEN.match(body, pos)
        if not m:
            raise ValueError("malformed TraX message %r" % line[:100])
        raw, pos = m.group(1) if m.group(1) is not None else m.group(2), m.end()
        named = NAMED.match(raw)
        if named:
            properties[named.group(1)] = unescape(named.group(2))
        else:
            arguments.append(unescape(raw))
    return name.lower(), arguments, properties


def decode_image(text):
    """A BGR (or gray) image from a "path" (file://..., or a bare path),
    "memory" (image:W;H;rgb|gray8|gray16;BASE64) or "buffer" (data:MIME;BASE64) argument."""
    if text.startswith("image:"):
        w, h, fmt, data = text[6:].split(";", 3)
        w, h = int(w), int(h)
        raw = base64.b64decode(data)
        if fmt == "rgb":
            return cv2.cvtColor(np.frombuffer(raw, np.uint8).reshape(h, w, 3), cv2.COLOR_RGB2BGR)
        if fmt == "gray8":
            return np.frombuffer(raw, np.uint8).reshape(h, w)
        if fmt == "gray16":
            return (np.frombuffer(raw, "<u2").reshape(h, w) >> 8).astype(np.uint8)
        raise ValueError("unknown memory image format %r" % fmt)
    if text.startswith("data:"):
        _, data = text[5:].split(";", 1)
        image = cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8), cv2.IMREAD_COLOR)
    else:
        path = text[7:] if text.startswith("file://") else text
        image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError("cannot read the image %r" % text[:100])
    return image


def parse_region(text):
    """(x, y, w, h) of a rectangle "x,y,w,h" or of the bounding box of a polygon "x1,y1,x2,y2,..."."""
    values = [float(v) for v in text.split(":")[-1].split(",")]
    if len(values) == 4:
        return tuple(values)
    if len(values) >= 6 and len(values) % 2 == 0:
        xs, ys = values[0::2], values[1::2]
        return min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)
    raise ValueError("not a rectangle or polygon: %r" % text)


def open_streams():
    """(input, output) binary files: the TCP connection if TRAX_SOCKET=PORT, else stdin/stdout."""
    port = os.environ.get("TRAX_SOCKET")
    if not port:
        return sys.stdin.buffer, sys.stdout.buffer
    for _ in range(100):
        try:
            conn = socket.create_connection(("127.0.0.1", int(port.rsplit(":", 1)[-1])))
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            return conn.makefile("rb"), conn.makefile("wb")
        except ConnectionRefusedError:
            time.sleep(0.1)
    raise SystemExit("cannot connect to TRAX_SOCKET=%s" % port)


def serve(make_tracker, name, image_formats=("path", "memory"), version=3):
    """Runs one TraX session: hello, then initialize/frame -> state until quit.
    make_tracker() returns an object with init(image, box) and update(image) -> box."""
    inp, out = open_streams()

    def send(*message):
        out.write(format_message(*message).encode("utf-8"))
        out.flush()

    def state(box):
        send("state", ["%.4f,%.4f,%.4f,%.4f" % tuple(box)])

    properties = {"trax.version": version, "trax.name": name, "trax.region": "rectangle;polygon;",
                  "trax.image": "".join(f + ";" for f in image_formats)}
    if version >= 2:
        properties["trax.channels"] = "color;"
    send("hello", [], properties)
    tracker, pending = None, []             # pending: version 4 regions waiting for their frame
    for raw in inp:
        try:
            message = parse_message(raw.decode("utf-8", "replace"))
            if message is None:
                continue                      # not for the protocol
            kind, args, _ = message
            if kind == "quit":
                break
            if kind == "initialize" and version < 4 and len(args) == 2:
                tracker = make_tracker()
                tracker.init(decode_image(args[0]), parse_region(args[1]))
                state(parse_region(args[1]))
            elif kind == "initialize" and version >= 4 and len(args) <= 1:
                if not args:                  # an empty initialize forgets all objects
                    tracker, pending = None, []
                else:
                    pending.append(parse_region(args[0]))
            elif kind == "frame" and len(args) == 1 and len(pending) == 1:
                tracker = make_tracker()
                tracker.init(decode_image(args[0]), pending[0])
                state(pending.pop())
            elif kind == "frame" and len(args) == 1 and tracker is not None and not pending:
                state(tracker.update(decode_image(args[0])))
            else:
                raise ValueError("unexpected message (this tracker follows one object): %r" % raw[:100])
        except Exception as e:                # tell the client why, then stop
            send("quit", [], {"trax.reason": "%s: %s" % (type(e).__name__, e)})
            raise SystemExit(1)


# --- The tracker -----------------------------------------------------------------

class NCCTracker:
    """Template matching by normalised cross-correlation (cv2.TM_CCOEFF_NORMED)
    in a window around the last box; the template follows the target slowly."""

    def __init__(self, search=0.75, learning_rate=0.05, min_score=0.5):
        self.search, self.rate, self.min_score = search, learning_rate, min_score

    @staticmethod
    def _gray(image):
        return (cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image).astype(np.float32)

    def _patch(self, gray, x, y, w, h):
        pad = w + h
        padded = cv2.copyMakeBorder(gray, pad, pad, pad, pad, cv2.BORDER_REPLICATE)
        x0, y0 = int(round(x)) + pad, int(round(y)) + pad
        x0, y0 = min(max(x0, 0), padded.shape[1] - w), min(max(y0, 0), padded.shape[0] - h)
        return padded[y0:y0 + h, x0:x0 + w]

    def init(self, image, box):
        x, y, w, h = box
        self.w, self.h = max(int(round(w)), 4), max(int(round(h)), 4)
        self.x, self.y = float(x), float(y)
        self.template = self._patch(self._gray(image), self.x, self.y, self.w, self.h).copy()

    def update(self, image):
        gray = self._gray(image)
        margin = int(max(8, self.search * max(self.w, self.h)))
        pad = margin + self.w + self.h
        padded = cv2.copyMakeBorder(gray, pad, pad, pad, pad, cv2.BORDER_REPLICATE)
        sx, sy = int(round(self.x)) - margin + pad, int(round(self.y)) - margin + pad
        window = padded[sy:sy + self.h + 2 * margin, sx:sx + self.w + 2 * margin]
        scores = np.nan_to_num(cv2.matchTemplate(window, self.template, cv2.TM_CCOEFF_NORMED))
        _, best, _, (bx, by) = cv2.minMaxLoc(scores)
        dx, dy = self._subpixel(scores, bx, by)
        x, y = sx - pad + bx + dx, sy - pad + by + dy      # keep the box overlapping the image
        self.x = min(max(x, 1.0 - self.w), gray.shape[1] - 1.0)
        self.y = min(max(y, 1.0 - self.h), gray.shape[0] - 1.0)
        if best > self.min_score:
            patch = self._patch(gray, self.x, self.y, self.w, self.h)
            self.template = (1 - self.rate) * self.template + self.rate * patch
        return self.x, self.y, float(self.w), float(self.h)

    @staticmethod
    def _subpixel(scores, bx, by):
        """Parabola through the peak and its neighbours, per axis."""
        def offset(a, b, c):
            d = a - 2 * b + c
            return 0.0 if d >= 0 else max(-0.5, min(0.5, 0.5 * (a - c) / d))
        h, w = scores.shape
        dx = offset(scores[by, bx - 1], scores[by, bx], scores[by, bx + 1]) if 0 < bx < w - 1 else 0.0
        dy = offset(scores[by - 1, bx], scores[by, bx], scores[by + 1, bx]) if 0 < by < h - 1 else 0.0
        return dx, dy


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--image-formats", default="path,memory",
                   help="comma-separated image formats to announce: path, memory, buffer (default: path,memory)")
    p.add_argument("--trax-version", type=int, default=3, choices=[1, 2, 3, 4],
                   help="TraX version to speak (4: initialize carries only the region)")
    p.add_argument("--name", default="ncc")
    args = p.parse_args()
    formats = [f for f in args.image_formats.split(",") if f]
    serve(NCCTracker, args.name, formats, args.trax_version)


if __name__ == "__main__":
    main()
