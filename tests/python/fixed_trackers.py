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


class Hanging(Broken):
    """Hangs in its third update(), as a tracker stuck in a loop or a lock does."""

    def update(self, image):
        import time
        if self.frames == 2:
            time.sleep(3600)
        return super().update(image)


class Banana:
    def init(self, image, box):
        pass

    def update(self, image):
        return "banana"


class Unstartable:
    def __init__(self):
        raise RuntimeError("no GPU here")


class Refused(Broken):
    """Answers boxes the daemon refuses: far outside the image, then infinite."""

    def update(self, image):
        self.frames += 1
        return (1e6, 1e6, 10.0, 10.0) if self.frames % 2 else (float("inf"), 0.0, 10.0, 10.0)


def hanging():
    return Hanging()


def banana():
    return Banana()


def unstartable():
    return Unstartable()


def refused():
    return Refused()
