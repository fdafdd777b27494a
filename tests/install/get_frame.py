"""A user's script outside the source tree: the pip-installed sim4cv starts the installed
sim4cvd by itself (no SIM4CVD: found on PATH) and reads one frame over shared memory.
Prints "frame ID WxH rgb_mean M from MODULE_FILE with DAEMON"; exits 1 on any error.
Run by tests/install/test_install.sh with the venv's python."""

import os
import sys

import sim4cv
from sim4cv.daemon import OwnDaemon, daemon_path


def main() -> int:
    shm_name = "/sim4cv-install-py-%d" % os.getpid()
    with OwnDaemon(["--shm-name", shm_name, "--shm-channels", "rgb"]) as daemon:
        client = sim4cv.connect("shm://" + daemon.fields["shm"])
        try:
            client.subscribe("uav", ["rgb"], "lockstep")
            frame = client.step_and_receive(timeout=60.0, copy=True)
        finally:
            client.close()
    rgb = frame.image(sim4cv.CHANNEL_RGB)
    if rgb.shape[:2] != (frame.height, frame.width) or frame.width == 0:
        print("get_frame.py: frame %d has an RGB image of shape %s" % (frame.frame_id, rgb.shape), file=sys.stderr)
        return 1
    print("frame %d %dx%d rgb_mean %.1f from %s with %s"
          % (frame.frame_id, frame.width, frame.height, rgb.mean(), sim4cv.__file__, daemon_path()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
