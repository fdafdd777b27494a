"""Shared command-line handling of the examples: --address and --frames, and
the package path when run from a source checkout."""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def parser(description, default_frames=300):
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--address", default="tcp://127.0.0.1:5000",
                   help="tcp://HOST:PORT, udp://HOST:PORT or shm://NAME of a running sim4cvd")
    p.add_argument("--frames", type=int, default=default_frames, help="how many frames to process")
    p.add_argument("--camera", default="uav", help="camera to subscribe to (over shm: the ring's camera)")
    return p
