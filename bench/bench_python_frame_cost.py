#!/usr/bin/python3
"""The Python shared-memory client's own cost per frame, without the daemon's render.

    /usr/bin/python3 bench/bench_python_frame_cost.py [--client-dir clients/python]

Starts a lockstep sim4cvd (320x180, ring channels rgb, depth, mask), steps a few frames, then
times in a loop (best of three repeats of 20,000 calls) what the client does for each frame
once it is published: reading the newest slot (seqlock, header, channel records, boxes,
entities: ShmFrame), taking numpy views of the three planes, and building a Step request.
--client-dir: the sim4cv package to time (e.g. an older checkout's clients/python).
"""

import argparse
import os
import sys
import timeit

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--client-dir", default=os.path.join(HERE, "..", "clients", "python"))
    p.add_argument("--calls", type=int, default=20000)
    args = p.parse_args()
    sys.path.insert(0, os.path.abspath(args.client_dir))
    import sim4cv
    from sim4cv._proto import pb
    from sim4cv.base import envelope
    from sim4cv.daemon import OwnDaemon

    with OwnDaemon(["--shm-name", "/s4cv-frame-cost-%d" % os.getpid(), "--log-level", "warning"]) as daemon:
        with sim4cv.connect("shm://" + daemon.fields["shm"], name="bench-frame-cost") as client:
            client.subscribe(client.ring_geometry.camera_name, ["rgb", "depth", "mask"], "lockstep")
            for _ in range(5):
                client.step_and_receive()
            ring = client._ring  # the mapped frame object: what receive_frame reads
            frame = ring.read_newest()
            parts = {
                "read the newest slot (ShmFrame)": ring.read_newest,
                "numpy views of rgb, depth, mask": lambda: (frame.image("rgb"), frame.image("depth"),
                                                            frame.image("mask")),
                "build and encode a Step": lambda: envelope(step=pb.Step()).SerializeToString(),
            }
            total = 0.0
            for name, call in parts.items():
                us = min(timeit.repeat(call, number=args.calls, repeat=3)) / args.calls * 1e6
                total += us
                print("%-34s %6.1f us" % (name, us))
            print("%-34s %6.1f us  (%s)" % ("sum", total, os.path.abspath(args.client_dir)))


if __name__ == "__main__":
    main()
