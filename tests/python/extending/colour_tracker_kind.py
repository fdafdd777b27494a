"""A tracker kind in one file: `colour:TOLERANCE` follows the first box's
mean colour (the first box's size, centred on the pixels within TOLERANCE
of that colour in every channel). Registered by one line,
register_tracker_kind("colour", "colour_tracker_kind"); the worked example
of docs/architecture.md, "Extending sim4cv"."""

import numpy as np

from sim4cv.trackers import Tracker

FORM = "colour:TOLERANCE"


def accepts(rest):
    return rest.isdigit()


def check(rest):
    if not 0 < int(rest) < 256:
        raise ValueError("colour:%s: TOLERANCE is a colour distance from 1 to 255" % rest)


def make(rest, target_id, timeout):
    return ColourTracker(int(rest))


class ColourTracker(Tracker):
    def __init__(self, tolerance):
        self.tolerance, self.name = tolerance, "colour:%d" % tolerance

    def _init(self, image, box, frame):
        x, y, w, h = (int(round(v)) for v in box)
        self._colour = image[y:y + h, x:x + w].reshape(-1, 3).mean(axis=0)
        self._size = box[2], box[3]

    def _update(self, image, frame):
        near = np.all(np.abs(image.astype(np.float32) - self._colour) <= self.tolerance, axis=2)
        rows, cols = np.nonzero(near)
        if rows.size == 0:
            return None
        (w, h) = self._size
        return (float(cols.mean()) + 0.5 - w / 2, float(rows.mean()) + 0.5 - h / 2, w, h)
