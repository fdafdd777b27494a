#!/usr/bin/python3
"""An OpenCV tracker in the loop: initialised on the first frame's
ground-truth box of the target (the car, object id 1), it tracks on every
RGB frame in lockstep and sends its box back as TrackerOutput; prints the
mean IoU with the ground truth.

    /usr/bin/python3 clients/python/examples/opencv_tracker.py --address tcp://127.0.0.1:5000 --frames 100

Needs Debian's python3-opencv (cv2).
"""

import cv2

from _common import parser

import sim4cv


def make_tracker(name):
    factories = {"kcf": "TrackerKCF_create", "mil": "TrackerMIL_create", "csrt": "TrackerCSRT_create"}
    factory = getattr(cv2, factories[name], None) or getattr(getattr(cv2, "legacy", None), factories[name], None)
    if factory is None:
        raise SystemExit("this OpenCV (%s) has no %s tracker" % (cv2.__version__, name))
    return factory()


def iou(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    w = max(0.0, min(ax + aw, bx + bw) - max(ax, bx))
    h = max(0.0, min(ay + ah, by + bh) - max(ay, by))
    union = aw * ah + bw * bh - w * h
    return w * h / union if union > 0 else 0.0


def main():
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--tracker", choices=["kcf", "mil", "csrt"], default="kcf")
    p.add_argument("--target", type=int, default=1, help="object id of the target (1: the car)")
    args = p.parse_args()
    tracker, ious = None, []
    with sim4cv.connect(args.address, name="opencv-" + args.tracker) as client:
        client.subscribe(args.camera, ["rgb", "boxes"], "lockstep")
        for frame in client.frames(step=True, count=args.frames):
            bgr = cv2.cvtColor(frame.image("rgb"), cv2.COLOR_RGB2BGR)  # a copy: the view may be shared memory
            truth = frame.box(args.target)
            if tracker is None:
                if truth is None:
                    continue  # wait until the target is visible
                tracker = make_tracker(args.tracker)
                tracker.init(bgr, (truth.x, truth.y, max(truth.width, 1), max(truth.height, 1)))
                box, ok = (truth.x, truth.y, truth.width, truth.height), True
            else:
                ok, box = tracker.update(bgr)
            x, y, w, h = (float(v) for v in box)
            client.send_tracker_output(frame.frame_id, x, y, w, h, 1.0 if ok else 0.0)
            if truth is not None:
                ious.append(iou((x, y, w, h), (truth.x, truth.y, truth.width, truth.height)))
    mean = sum(ious) / len(ious) if ious else 0.0
    print("tracked %d frames with %s over %s: mean IoU %.3f" % (len(ious), args.tracker, args.address, mean))


if __name__ == "__main__":
    main()
