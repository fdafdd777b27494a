#!/usr/bin/python3
"""Drives the car: every lockstep frame, a simple controller steers towards
the middle of the car's box in the UAV image, holds a cruising throttle, and
sends Controls; prints the distance the car covered.

    /usr/bin/python3 clients/python/examples/drive.py --address udp://127.0.0.1:5001 --frames 300
"""

import math

from _common import parser

import sim4cv


def main():
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--throttle", type=float, default=0.4)
    args = p.parse_args()
    with sim4cv.connect(args.address, name="driver") as client:
        car = next(e.id for e in client.welcome.entities if e.kind == sim4cv.ENTITY_KIND_CAR)
        client.subscribe(args.camera, ["rgb", "boxes"], "lockstep")
        start = client.get_state()
        for n, frame in enumerate(client.frames(step=True, count=args.frames)):
            box = frame.box(car)
            steering = 0.0
            if box is not None:  # keep the car in the middle of the picture: a gentle weave
                offset = (box.x + box.width / 2) / frame.width - 0.5
                steering = max(-1.0, min(1.0, -2.0 * offset + 0.3 * math.sin(n / 30)))
            client.send_controls(car, steering, args.throttle, 0.0)
        end = client.get_state()
    a = next(e.position for e in start.entities if e.id == car)
    b = next(e.position for e in end.entities if e.id == car)
    print("drove car %d for %d frames over %s: %.2f m" % (car, args.frames, args.address,
                                                          math.hypot(b.x - a.x, b.y - a.y)))


if __name__ == "__main__":
    main()
