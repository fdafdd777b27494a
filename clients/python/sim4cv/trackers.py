"""Tracker specifications: one string names a tracker everywhere sim4cv
takes one (the command line, experiment files; docs/tracking.md).

    gt                      the ground truth: each frame's true box of the target
    baseline:static         the first box forever; baseline:centre: the first box's size at the image centre
    opencv:NAME             an OpenCV 4.6 tracker: MOSSE, KCF, CSRT, MIL, MedianFlow, TLD, Boosting
    trax:COMMAND LINE       any TraX tracker process (sim4cv.trax; every VOT tracker)
    python:MODULE:FACTORY   FACTORY() from MODULE: an object with init(image, box) and update(image) -> box
    octave:FILE.m           a tracker in plain Octave/MATLAB, run as a TraX server (docs/trax.md)

Every tracker here has `init(image, box)` and `update(image) -> box or
None` (None: no estimate for this frame), `close()` and `name`; images are
HxWx3 uint8 RGB, boxes (x, y, w, h) in pixels with the top-left corner of
the top-left pixel at (0, 0). The ground-truth tracker needs the frame:
`update(image, frame=...)` on every tracker takes it and only `gt` reads it.
"""

import os
from typing import Optional, Sequence, Tuple

import numpy as np

BoxTuple = Tuple[float, float, float, float]

# OpenCV 4.6's trackers by name: where cv2 keeps each (main module or legacy).
_OPENCV = {
    "mosse": ("legacy", "TrackerMOSSE_create"),
    "kcf": ("", "TrackerKCF_create"),
    "csrt": ("", "TrackerCSRT_create"),
    "mil": ("", "TrackerMIL_create"),
    "medianflow": ("legacy", "TrackerMedianFlow_create"),
    "tld": ("legacy", "TrackerTLD_create"),
    "boosting": ("legacy", "TrackerBoosting_create"),
    "goturn": ("", "TrackerGOTURN_create"),
    "dasiamrpn": ("", "TrackerDaSiamRPN_create"),
}


class Tracker:
    """What every tracker offers; subclasses implement _init and _update."""

    name = "tracker"

    def init(self, image: np.ndarray, box: Sequence[float], frame=None) -> None:
        self._init(image, tuple(float(v) for v in box), frame)

    def update(self, image: np.ndarray, frame=None) -> Optional[BoxTuple]:
        return self._update(image, frame)

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _init(self, image, box, frame):
        raise NotImplementedError

    def _update(self, image, frame):
        raise NotImplementedError


class GroundTruthTracker(Tracker):
    """The reference run: answers each frame with the target's true visible
    box, and nothing while the target is hidden (as an annotation would)."""

    name = "gt"

    def __init__(self, target_id: int = 0):
        self.target_id = target_id

    def _init(self, image, box, frame):
        pass

    def _update(self, image, frame):
        if frame is None:
            raise ValueError("the ground-truth tracker needs the frame: update(image, frame=frame)")
        box = frame.box(self.target_id)
        if box is None or box.visibility <= 0:
            return None
        return (float(box.x), float(box.y), float(box.width), float(box.height))


class StaticBaseline(Tracker):
    """`baseline:static`: the first box, forever. A benchmark in which doing
    nothing scores well does not measure tracking; this shows how well."""

    name = "baseline:static"

    def _init(self, image, box, frame):
        self._box = box

    def _update(self, image, frame):
        return self._box


class CentreBaseline(Tracker):
    """`baseline:centre`: the first box's size, centred in the image: what a
    camera that always centres its target would give for free."""

    name = "baseline:centre"

    def _init(self, image, box, frame):
        self._size = box[2], box[3]

    def _update(self, image, frame):
        (w, h), (rows, cols) = self._size, image.shape[:2]
        return ((cols - w) / 2.0, (rows - h) / 2.0, w, h)


BASELINES = {"baseline:static": StaticBaseline, "baseline:centre": CentreBaseline}


class OpenCvTracker(Tracker):
    """One of OpenCV's trackers (cv2, Debian's python3-opencv: the same C++
    implementations a C++ client links)."""

    def __init__(self, kind: str):
        import cv2
        key = kind.lower()
        if key not in _OPENCV:
            raise ValueError("opencv:%s is not an OpenCV tracker; choose one of %s"
                             % (kind, ", ".join(sorted(_OPENCV))))
        where, factory_name = _OPENCV[key]
        module = getattr(cv2, where) if where else cv2
        factory = getattr(module, factory_name, None)
        if factory is None:
            raise ValueError("this OpenCV (%s) has no %s tracker" % (cv2.__version__, kind))
        self._factory = factory
        self._cv2 = cv2
        self._tracker = None
        self.name = "opencv:" + key

    def _init(self, image, box, frame):
        self._tracker = self._factory()
        bgr = self._cv2.cvtColor(image, self._cv2.COLOR_RGB2BGR)
        x, y, w, h = box
        self._tracker.init(bgr, (int(round(x)), int(round(y)), max(1, int(round(w))), max(1, int(round(h)))))

    def _update(self, image, frame):
        # OpenCV 4.6's MOSSE and KCF answer (False, (0, 0, 0, 0)) when their
        # own test fails (MOSSE's peak-to-sidelobe ratio, KCF's peak): there
        # is no box to use, so that is no answer (None), as a zero-size box is.
        _, box = self._tracker.update(self._cv2.cvtColor(image, self._cv2.COLOR_RGB2BGR))
        x, y, w, h = (float(v) for v in box)
        return (x, y, w, h) if w > 0 and h > 0 else None


class PythonTracker(Tracker):
    """FACTORY() from MODULE, in a process of its own (sim4cv.python_tracker):
    each call may take `timeout` seconds, as a TraX tracker's, after which
    its process tree is killed; junk answers are errors naming the tracker."""

    def __init__(self, module: str, factory: str, timeout: float = 30.0):
        from .python_tracker import TrackerProcess
        self._tracker = TrackerProcess(module, factory, timeout)
        self.name = self._tracker.name

    def _init(self, image, box, frame):
        self._tracker.call("init", image, box)

    def _update(self, image, frame):
        from .python_tracker import check_box
        return check_box(self.name, self._tracker.call("update", image))

    def close(self):
        self._tracker.close()


class TraxTrackerAdapter(Tracker):
    """A TraX tracker process (sim4cv.trax.TraxTracker); `octave:FILE.m`
    runs as one too."""

    def __init__(self, spec: str, timeout: float = 30.0):
        from . import trax
        self._tracker = trax.open_tracker(spec, timeout=timeout)
        self.name = spec

    def _init(self, image, box, frame):
        self._tracker.init(image, box)

    def _update(self, image, frame):
        return self._tracker.update(image)

    def close(self):
        self._tracker.close()


class TrackerKind:
    """A kind of tracker, named by the prefix before a specification's first
    ':' ("opencv" in opencv:KCF). `form` says how it is written, for
    messages; `accepts(rest)` whether REST (after the ':'; "" without one)
    has that form; `check(rest)` raises ValueError naming what is wrong
    without starting anything (experiment files are checked with it before
    any run); `make(rest, target_id, timeout)` builds the Tracker."""

    def __init__(self, form, make, accepts=bool, check=None):
        self.form, self.make, self.accepts = form, make, accepts
        self.check = check or (lambda rest: None)


# The tracker kinds by prefix. A kind in a module of its own (with FORM,
# accepts, make and optionally check at module level) is registered by one
# line, register_tracker_kind("PREFIX", "package.module"), and imported
# only when a specification names it (docs/architecture.md, "Extending sim4cv").
TRACKER_KINDS = {}


def register_tracker_kind(prefix, kind):
    """Registers `kind` (a TrackerKind, or the name of a module that has
    FORM, accepts, make and maybe check) for specifications PREFIX[:REST]."""
    if ":" in prefix or not prefix:
        raise ValueError("a tracker kind's prefix is one word without ':', not %r" % (prefix,))
    TRACKER_KINDS[prefix] = kind


def _kind(prefix):
    kind = TRACKER_KINDS.get(prefix)
    if isinstance(kind, str):
        import importlib
        module = importlib.import_module(kind)
        kind = TRACKER_KINDS[prefix] = TrackerKind(module.FORM, module.make, module.accepts,
                                                   getattr(module, "check", None))
    return kind


def _check_opencv(rest):
    if rest.lower() not in _OPENCV:
        raise ValueError("unknown tracker specification %r (OpenCV trackers: %s)"
                         % ("opencv:" + rest, ", ".join(sorted(_OPENCV))))


def _check_octave(rest):
    if not rest.strip().endswith(".m"):
        raise ValueError("unknown tracker specification %r (forms: %s)" % ("octave:" + rest, tracker_forms()))
    if not os.path.isfile(os.path.abspath(rest.strip())):
        raise ValueError("%r: no file %s (paths are relative to the working directory)"
                         % ("octave:" + rest, os.path.abspath(rest.strip())))


def _python_parts(rest):
    return rest.count(":") == 1 and all(rest.split(":"))


register_tracker_kind("gt", TrackerKind("gt", lambda rest, target_id, timeout: GroundTruthTracker(target_id),
                                        accepts=lambda rest: rest == ""))
register_tracker_kind("baseline", TrackerKind(", ".join(BASELINES), lambda rest, target_id, timeout:
                                              BASELINES["baseline:" + rest](), accepts=lambda rest:
                                              "baseline:" + rest in BASELINES))
register_tracker_kind("opencv", TrackerKind("opencv:NAME", lambda rest, target_id, timeout: OpenCvTracker(rest),
                                            check=_check_opencv))
register_tracker_kind("trax", TrackerKind("trax:COMMAND LINE", lambda rest, target_id, timeout:
                                          TraxTrackerAdapter("trax:" + rest, timeout),
                                          accepts=lambda rest: bool(rest.strip())))
register_tracker_kind("python", TrackerKind("python:MODULE:FACTORY", lambda rest, target_id, timeout:
                                            PythonTracker(*rest.split(":"), timeout), accepts=_python_parts))
register_tracker_kind("octave", TrackerKind("octave:FILE.m", lambda rest, target_id, timeout:
                                            TraxTrackerAdapter("octave:" + rest, timeout),
                                            accepts=lambda rest: bool(rest.strip()), check=_check_octave))


def tracker_forms():
    """"gt, baseline:static, ...": every registered kind's form, for messages."""
    return ", ".join(_kind(prefix).form for prefix in list(TRACKER_KINDS))


def _find_kind(spec):
    """(kind, rest) for a specification of a registered kind's form, else ValueError naming the forms."""
    prefix, colon, rest = spec.partition(":")
    kind = _kind(prefix) if prefix in TRACKER_KINDS else None
    if kind is None or (colon and not rest) or not kind.accepts(rest):
        raise ValueError("tracker specification %r is none of: %s" % (spec, tracker_forms()))
    return kind, rest


def check_tracker_spec(spec):
    """`spec`, stripped, if make_tracker would accept it (without starting it:
    no process, no import of a python: module); else ValueError naming it."""
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError("%r is not a tracker specification" % (spec,))
    spec = spec.strip()
    try:
        kind, rest = _find_kind(spec)
    except ValueError:
        raise ValueError("unknown tracker specification %r (forms: %s)" % (spec, tracker_forms())) from None
    kind.check(rest)
    return spec


def make_tracker(spec: str, target_id: int = 0, timeout: float = 30.0) -> Tracker:
    """The tracker a specification names (module docstring; TRACKER_KINDS).
    ValueError, naming the specification and the accepted forms, for anything else."""
    kind, rest = _find_kind(spec.strip())
    return kind.make(rest, target_id, timeout)
