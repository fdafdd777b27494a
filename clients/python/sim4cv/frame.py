"""The frame type every transport returns: sim4cv.Frame.

Over TCP and UDP a Frame wraps the received protobuf Frame (`.message`) and
its images are views of the received bytes. Over shared memory a ShmFrame
(shm.py, a subclass) views the ring slot itself, and `.message` is None.
"""

from typing import Dict, List, NamedTuple, Optional, Tuple

import numpy as np

from ._proto import pb
from .images import channel_name, channel_value, image_array


class Box(NamedTuple):
    """A ground-truth box (the fields of pb.Box): pixels, top-left origin."""
    object_id: int
    object_class: int
    x: int
    y: int
    width: int
    height: int
    visibility: float
    visible_pixels: int


class EntityPose(NamedTuple):
    """An entity's pose and velocity (the fields of pb.EntityState but its name)."""
    id: int
    kind: int
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]  # w, x, y, z
    linear_velocity: Tuple[float, float, float]
    angular_velocity: Tuple[float, float, float]


def _vec(v, fields="xyz"):
    return tuple(float(getattr(v, f)) for f in fields)


class Frame:
    """One camera frame.

    frame_id, sim_time (s), render_end_mono_ns (CLOCK_MONOTONIC, comparable
    with time.monotonic_ns()), width, height, camera (name; "" over shared
    memory), boxes (list of Box), entities (list of EntityPose; empty unless
    the frame carried state), message (the pb.Frame, or None over shared
    memory). image(channel) returns a numpy array of a pixel channel.
    """

    __slots__ = ("frame_id", "sim_time", "render_end_mono_ns", "width", "height", "camera", "boxes",
                 "entities", "message", "_images")

    def __init__(self, frame_id: int, sim_time: float, render_end_mono_ns: int, width: int, height: int,
                 boxes: List[Box], entities: List[EntityPose], images: Dict[int, np.ndarray],
                 message: Optional["pb.Frame"] = None, camera: str = ""):
        self.frame_id = int(frame_id)
        self.sim_time = float(sim_time)
        self.render_end_mono_ns = int(render_end_mono_ns)
        self.width = int(width)
        self.height = int(height)
        self.camera = camera
        self.boxes = boxes
        self.entities = entities
        self.message = message
        self._images = images  # channel value -> array (copied frames); None: taken from message

    @classmethod
    def from_message(cls, message: "pb.Frame") -> "Frame":
        """Wraps a received pb.Frame (no pixel copies)."""
        boxes = [Box(b.object_id, b.object_class, b.x, b.y, b.width, b.height, b.visibility, b.visible_pixels)
                 for b in message.boxes]
        entities = []
        if message.HasField("state"):
            entities = [EntityPose(e.id, e.kind, _vec(e.position), _vec(e.orientation, "wxyz"),
                                   _vec(e.linear_velocity), _vec(e.angular_velocity))
                        for e in message.state.entities]
        return cls(message.frame_id, message.sim_time, message.render_end_mono_ns, message.width, message.height,
                   boxes, entities, None, message, message.camera)

    @property
    def channels(self) -> List[int]:
        """The pixel channels (Channel values) this frame carries."""
        if self._images is not None:
            return list(self._images)
        return [image.channel for image in self.message.images]

    def image(self, channel) -> np.ndarray:
        """The pixels of `channel` ("rgb", "depth", "mask", ... or a Channel
        value): RGB (h, w, 3) uint8, DEPTH (h, w) float32, MASK (h, w)
        uint16, others shaped by their element type and components. A
        read-only view of the received bytes. KeyError if not carried."""
        if self._images is None:
            return image_array(self.message, channel)
        try:
            return self._images[channel_value(channel)]
        except KeyError:
            raise KeyError("frame %d does not carry channel %s" % (self.frame_id, channel_name(channel))) from None

    def box(self, object_id: int) -> Optional[Box]:
        """The ground-truth box of `object_id`, or None if it is not visible."""
        for b in self.boxes:
            if b.object_id == object_id:
                return b
        return None

    def age_ns(self) -> int:
        """time.monotonic_ns() minus render_end_mono_ns: how old the frame is now."""
        import time
        return time.monotonic_ns() - self.render_end_mono_ns

    def __repr__(self):
        return "<%s %d %dx%d t=%.3f %s>" % (type(self).__name__, self.frame_id, self.width, self.height,
                                           self.sim_time, ",".join(channel_name(c)[8:].lower() for c in self.channels))
