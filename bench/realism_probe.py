#!/usr/bin/python3
"""The realism probe (docs/gallery.md, "Realism probe"): do detectors trained
on real photographs find sim4cv's walkers? For each conditions preset it
starts its own sim4cvd (lockstep) on a map with traffic, spawns walkers along
the target car's lane, and for a seeded set of frames puts a 640x480 camera
4.5-6.5 m in front of or behind a walker at eye level (a spawned one, or on
odd frames the nearest traffic walker, when there is one). The walkers the
ground truth lists as OBJECT_CLASS_PEDESTRIAN with a box at least 96 px tall,
visibility >= 0.5 and not touching the image border are the ones to find;
OpenCV's default (INRIA) and Daimler HOG people detectors and its Haar
full- and upper-body cascades run on each RGB frame (matching rules in
bench/realism_detectors.py). Also runs them on packaged real photographs
and video with people. Writes JSON and a Markdown table, the same bytes
for the same arguments.

  /usr/bin/python3 bench/realism_probe.py --out build/realism [--frames 33] [--seed 1]
      [--presets clear_noon,overcast] [--save-frames] [--photos FILE ...]
"""

import argparse
import json
import math
import os
import random
import signal
import sys
import time

import cv2

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "clients", "python"))

import realism_detectors as det  # noqa: E402
import sim4cv  # noqa: E402
from sim4cv.daemon import REPO_ROOT, OwnDaemon  # noqa: E402

PEDESTRIAN = 7  # OBJECT_CLASS_PEDESTRIAN
WIDTH, HEIGHT, FOV_Y = 640, 480, 60.0
MIN_HEIGHT_PX, MIN_VISIBILITY = 96, 0.5
MAP = "scenes/driving/train/01_urban.map"
TRAFFIC = ["--traffic-cars", "12", "--traffic-parked", "20", "--traffic-pedestrians", "16"]
WALKERS = 8           # spawned walkers, pacing 12 m of lane each
STEPS_BETWEEN = 4     # frames simulated between two probe frames (walkers move on)
EYE_HEIGHT = 1.6      # camera height, m
# Real photographs with people that Debian packages ship (none annotated).
OPENCV_DOC_DATA = "/usr/share/doc/opencv-doc/examples/data/"  # opencv-doc
SKIMAGE_DATA = "/usr/lib/python3/dist-packages/skimage/data/"  # python3-skimage
PACKAGED_PHOTOS = [OPENCV_DOC_DATA + "vtest.avi", OPENCV_DOC_DATA + "basketball1.png", OPENCV_DOC_DATA + "messi5.jpg",
                   SKIMAGE_DATA + "astronaut.png", SKIMAGE_DATA + "camera.png"]


def spawn_walkers(client, rng):
    """WALKERS pedestrians pacing to and fro on the target car's lane ahead of it; their ids."""
    car = next(e for e in client.get_state().entities if e.name == "car")
    road = client.query_road(car.position.x, car.position.y, count=60, step=6.0)
    ids = []
    for index in sorted(rng.sample(range(4, len(road.ahead) - 2), WALKERS)):
        path = [(p.position.x, p.position.y) for p in road.ahead[index:index + 3]]  # out along 12 m and back
        walker = client.spawn("pedestrian", "probe_walker_%d" % len(ids), path[0][0], path[0][1], 0.0)
        client.set_waypoints(walker, path, closed=True,
                             speed=round(rng.uniform(1.0, 1.6), 2))
        ids.append(walker)
    return ids


def camera_pose_towards(position, heading_deg, rng):
    """Eye level, 4.5-6.5 m ahead of or behind the walker, within 35 degrees of its path, facing it."""
    distance = rng.uniform(4.5, 6.5)
    bearing = math.radians(heading_deg + rng.choice([0.0, 180.0]) + rng.uniform(-35.0, 35.0))
    x, y = position[0] + distance * math.cos(bearing), position[1] + distance * math.sin(bearing)
    yaw = math.degrees(math.atan2(position[1] - y, position[0] - x))
    pitch = math.degrees(math.atan2(EYE_HEIGHT - 0.9, distance))
    return x, y, yaw, pitch


def next_target(frame, walkers, index):
    """The walker the next frame is aimed at: (id, position, velocity). Odd frames: the traffic walker
    nearest to the camera among those the last frame's 3D ground truth holds, if any;
    else, and on even frames, one of the spawned walkers in turn."""
    if index % 2 == 1:
        camera = frame.message.camera_pose.position
        traffic = [o for o in frame.message.objects if o.object_class == PEDESTRIAN and o.object_id not in walkers]
        if traffic:
            nearest = min(traffic, key=lambda o: ((o.position.x - camera.x) ** 2 + (o.position.y - camera.y) ** 2,
                                                  o.object_id))
            velocity = nearest.linear_velocity
            return nearest.object_id, (nearest.position.x, nearest.position.y), (velocity.x, velocity.y)
    target = walkers[(index // 2) % len(walkers)]
    pose = next(e for e in frame.entities if e.id == target)
    return target, pose.position, pose.linear_velocity


def walkers_to_find(frame, mask):
    """Every pedestrian box of the frame with the reason it is (or is not) one to find."""
    listed = []
    for box in frame.boxes:
        if box.object_class != PEDESTRIAN:
            continue
        xywh = (box.x, box.y, box.width, box.height)
        touches = box.x == 0 or box.y == 0 or box.x + box.width == WIDTH or box.y + box.height == HEIGHT
        reason = ("shorter than %d px" % MIN_HEIGHT_PX if box.height < MIN_HEIGHT_PX else
                  "visibility below %.1f" % MIN_VISIBILITY if box.visibility < MIN_VISIBILITY else
                  "cut by the image border" if touches else "")
        listed.append({"object_id": box.object_id, "box": list(xywh), "visibility": round(box.visibility, 4),
                       "visible_pixels": box.visible_pixels, "to_find": not reason, "excluded": reason})
    return listed


def run_preset(preset, args, detectors, frame_dir):
    rng = random.Random(args.seed)
    flags = ["--map", os.path.join(REPO_ROOT, MAP), "--seed", str(args.seed), "--conditions", preset] + TRAFFIC
    frames = []
    with OwnDaemon(flags) as daemon, sim4cv.connect(daemon.address, name="realism-probe") as client:
        walkers = spawn_walkers(client, rng)
        client.add_camera("probe", width=WIDTH, height=HEIGHT, fov_y_deg=FOV_Y, offset=(0.0, 0.0, EYE_HEIGHT))
        client.subscribe("probe", ["rgb", "mask", "boxes"], "lockstep", with_state=True)
        frame = client.step_and_receive(timeout=60.0)
        for index in range(args.frames):
            for _ in range(STEPS_BETWEEN):
                frame = client.step_and_receive(timeout=60.0)
            target, position, velocity = next_target(frame, walkers, index)
            heading = math.degrees(math.atan2(velocity[1], velocity[0]))
            x, y, yaw, pitch = camera_pose_towards(position, heading, rng)
            client.set_camera_pose("probe", x, y, EYE_HEIGHT, yaw, pitch)
            frame = client.step_and_receive(timeout=60.0)
            bgr = cv2.cvtColor(frame.image("rgb"), cv2.COLOR_RGB2BGR)
            mask = frame.image("mask").copy()
            record = {"frame_id": frame.frame_id, "walker_aimed_at": target, "traffic_walker": target not in walkers, "pedestrians": walkers_to_find(frame, mask)}
            gt = [tuple(p["box"]) for p in record["pedestrians"] if p["to_find"]]
            for name, detect in detectors.items():
                boxes = detect(bgr)
                rule = "upper" if name == "haar_upperbody" else "raw" if name == "haar_fullbody" else "body"
                found, false_positives = det.match(boxes, gt, rule)
                record[name] = {"boxes": [list(b) for b in boxes], "found": len(found), "false_positives": false_positives}
                if name.startswith("hog"):
                    record[name]["found_raw_iou"] = len(det.match(boxes, gt, "raw")[0])
            if frame_dir:
                stem = os.path.join(frame_dir, "%s_%03d" % (preset, index))
                cv2.imwrite(stem + "_rgb.png", bgr)
                cv2.imwrite(stem + "_mask.png", mask)  # 16-bit PNG of object ids
            frames.append(record)
    return frames


def summarise(frames, detector_names):
    walkers = sum(sum(p["to_find"] for p in f["pedestrians"]) for f in frames)
    summary = {"frames": len(frames), "walkers": walkers}
    for name in detector_names:
        found = sum(f[name]["found"] for f in frames)
        entry = {"found": found, "recall": round(found / walkers, 4) if walkers else None,
                 "false_positives_per_frame": round(sum(f[name]["false_positives"] for f in frames) / len(frames), 3)}
        if name.startswith("hog"):
            entry["found_raw_iou"] = sum(f[name]["found_raw_iou"] for f in frames)
        summary[name] = entry
    return summary


def markdown(result):
    names = result["detectors"]
    lines = ["| preset | frames | walkers | " + " | ".join(names) + " |", "|---|---|---|" + "---|" * len(names)]
    for preset, summary in result["summary"].items():
        cells = []
        for name in names:
            s = summary[name]
            recall = "%.1f %%" % (100 * s["recall"]) if s["recall"] is not None else "-"
            cells.append("%d (%s), %.2f FP/frame" % (s["found"], recall, s["false_positives_per_frame"]))
        lines.append("| %s | %d | %d | %s |" % (preset, summary["frames"], summary["walkers"], " | ".join(cells)))
    lines.append("")
    lines.append("Packaged real photographs (not annotated; how many boxes each detector returns):")
    lines.append("")
    for photo in result["photos"]:
        counts = ", ".join("%s %d" % (n, len(photo.get(n, []))) for n in names) if "error" not in photo else photo["error"]
        lines.append("- `%s`: %s" % (photo["photo"], counts))
    if not result["photos"]:
        lines.append("- none found (install opencv-doc or python3-skimage, or pass --photos)")
    lines.append("")
    lines.append("Offline car detectors packaged with OpenCV: %s" % (", ".join(result["car_detectors"]) or "none"))
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True, help="folder for realism_probe.json and realism_probe.md")
    parser.add_argument("--frames", type=int, default=33, help="probe frames per preset")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--presets", default="clear_noon,overcast")
    parser.add_argument("--save-frames", action="store_true", help="also write each frame's RGB and mask PNGs")
    parser.add_argument("--photos", nargs="*", default=None, help="real photographs (default: the packaged ones present)")
    args = parser.parse_args(argv)
    # SIGTERM unwinds like Ctrl-C, so the daemon this probe started is stopped too.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    os.makedirs(args.out, exist_ok=True)
    start = time.monotonic()
    detectors = dict(det.hog_detectors(), **det.haar_detectors())
    frame_dir = os.path.join(args.out, "frames") if args.save_frames else ""
    if frame_dir:
        os.makedirs(frame_dir, exist_ok=True)
    photos = args.photos if args.photos is not None else [p for p in PACKAGED_PHOTOS if os.path.isfile(p)]
    result = {"map": MAP, "traffic": TRAFFIC, "seed": args.seed, "width": WIDTH, "height": HEIGHT,
              "min_height_px": MIN_HEIGHT_PX, "min_visibility": MIN_VISIBILITY, "detectors": list(detectors),
              "hog_params": {k: list(v) if isinstance(v, tuple) else v for k, v in det.HOG_PARAMS.items()},
              "haar_params": det.HAAR_PARAMS, "car_detectors": det.packaged_car_detectors(),
              "summary": {}, "frames": {}, "photos": []}
    for preset in args.presets.split(","):
        frames = run_preset(preset, args, detectors, frame_dir)
        result["frames"][preset] = frames
        result["summary"][preset] = summarise(frames, list(detectors))
    result["photos"] = [image for p in photos for image in det.probe_photo(p, detectors)]
    with open(os.path.join(args.out, "realism_probe.json"), "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)
    table = markdown(result)
    with open(os.path.join(args.out, "realism_probe.md"), "w") as f:
        f.write(table)
    sys.stdout.write(table)
    print("realism probe: %.1f s" % (time.monotonic() - start))
    return 0


if __name__ == "__main__":
    sys.exit(main())
