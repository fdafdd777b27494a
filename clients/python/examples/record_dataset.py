#!/usr/bin/python3
"""Records a small tracking data set: N lockstep frames as RGB PNGs plus
boxes.csv (one row per ground-truth box: frame, file, object_id, class, x,
y, width, height, visibility).

    /usr/bin/python3 clients/python/examples/record_dataset.py --address shm:///sim4cv-demo --frames 100 --out data
"""

import csv
import os
import struct
import zlib

import numpy as np

from _common import parser

import sim4cv


def write_png(path, rgb):
    """An RGB PNG with zlib alone (no imaging library needed)."""
    h, w, _ = rgb.shape
    raw = np.zeros((h, w * 3 + 1), np.uint8)
    raw[:, 1:] = rgb.reshape(h, w * 3)  # filter byte 0 per row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw.tobytes(), 3)) + chunk(b"IEND", b""))


def main():
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--out", default="sim4cv-dataset", help="output folder")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = 0
    with sim4cv.connect(args.address, name="recorder") as client, \
            open(os.path.join(args.out, "boxes.csv"), "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["frame_id", "file", "object_id", "object_class", "x", "y", "width", "height", "visibility"])
        client.subscribe(args.camera, ["rgb", "boxes"], "lockstep")
        for frame in client.frames(step=True, count=args.frames, copy=True):  # copies: safe to keep
            name = "%06d.png" % frame.frame_id
            write_png(os.path.join(args.out, name), frame.image("rgb"))
            for b in frame.boxes:
                out.writerow([frame.frame_id, name, b.object_id, b.object_class, b.x, b.y, b.width, b.height,
                              "%.3f" % b.visibility])
                rows += 1
    print("recorded %d frames and %d boxes from %s into %s" % (args.frames, rows, args.address, args.out))


if __name__ == "__main__":
    main()
