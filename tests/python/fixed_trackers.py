"""Trackers for tests/python/test_tracking.py, named as python:fixed_trackers:FACTORY."""


class Corner:
    """Answers every frame with a box in the image's top-left corner: the
    servo steers the UAV towards it and loses the target."""

    def init(self, image, box):
        pass

    def update(self, image):
        return (0.0, 0.0, 20.0, 20.0)


class Broken:
    """Fails on its third frame, as a buggy tracker does."""

    def __init__(self):
        self.frames = 0

    def init(self, image, box):
        pass

    def update(self, image):
        self.frames += 1
        if self.frames == 3:
            raise ZeroDivisionError("the filter blew up on frame 3")
        return None


def corner():
    return Corner()


def broken():
    return Broken()
