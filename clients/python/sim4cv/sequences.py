"""Synthetic UAV tracking sequences in the OTB / UAV123 folder format, with
exact ground truth and automatic attributes (sim4cv.attributes).

    python3 -m sim4cv.sequences generate --out DIR [--maps tracking/easy_urban,...] [--speeds 4,6,8]
                                         [--frames N | --laps L] [--preset paper] [--conditions PRESET]
                                         [--channels depth,mask] [--daemon ADDRESS] [--jobs J]
    python3 -m sim4cv.sequences attributes --out DIR     # recompute the attribute files from the folders
    python3 -m sim4cv.sequences maps                     # the shipped tracking maps
    python3 -m sim4cv.sequences stats DIR [--json F]     # camera-motion statistics (sim4cv.sequence_stats)
    python3 -m sim4cv.sequences export DIR --format uav123|got10k|otb --out OUT   (sim4cv.sequence_export)
    python3 -m sim4cv.sequences export-results RESULTS --layout got10k|pytracking --out OUT

For each (map, speed) the tool starts its own sim4cvd (`--map
scenes/tracking/<name>.map --car-speed S --mode lockstep`; $SIM4CVD or
build/server/daemon/sim4cvd), or with --daemon loads the map into that daemon,
and films the map's car (the target), lockstep, rgb + boxes (+ channels)
with state: by default through a world-fixed camera like the UAV's camera
"uav", flown by sim4cv.pilot (a pilot model: lag, limited rates, wind,
manoeuvres; the UAV is removed), or with camera_motion "servo" through the
camera "uav" of the map's UAV following the car. Per sequence
DIR/<map>_s<speed>[_<conditions>]/:

    img/000001.jpg ...          RGB, JPEG quality 95
    groundtruth_rect.txt        x,y,w,h per frame, 0-based pixels, box = [x, x+w) x [y, y+h);
                                NaN,NaN,NaN,NaN where the target has no visible pixel
    poses.csv                   frame, frame_id, sim_time, uav pose, target pose (yaw in degrees),
                                visibility, visible pixels, camera pose
    pilot.csv                   (pilot) per frame: manoeuvre, framing offsets, wind
    measures.csv                frame, in_view, the target's projected box, box luma, BC similarity,
                                similar-object distance (the attributes' image inputs)
    depth/000001.npy, mask/000001.png, ...   with --channels
    attributes.txt, attributes_per_frame.csv
    sequence.json               settings, camera intrinsics, daemon version, "complete"

and DIR/attribute_names.txt. docs/tracking.md, "Sequences and attributes".
"""

import concurrent.futures
import glob
import json
import math
import os
import shutil
import sys
import time
import zlib

import numpy as np

from . import attributes as attrs
from .channel_table import PIXEL_CHANNELS
from .daemon import REPO_ROOT, OwnDaemon
from .pilot import MODEL as PILOT_MODEL

MAPS_DIR = os.path.join(REPO_ROOT, "scenes")
TRACKING_MAPS = ["tracking/easy_desert", "tracking/easy_urban", "tracking/hard_desert", "tracking/hard_urban"]
DEFAULT_SPEEDS = (4.0, 6.0, 8.0)
EXTRA_CHANNELS = tuple(row[0] for row in PIXEL_CHANNELS if row[0] != "rgb")  # saved beside img/, one folder each
CONDITIONS = ("clear_noon", "clear_morning", "overcast", "fog", "dusk", "night", "rain")
JPEG_QUALITY = 95
PIPELINE_STEPS = 4  # lockstep Steps kept outstanding, so rendering overlaps our JPEG encoding
# pilot: sim4cv.pilot flies a world-fixed camera (the default); servo: the map's UAV follows the car
CAMERA_MOTIONS = ("pilot", "servo")
PILOT_CAMERA = "pilot"

# The paper's offline set: 5 sequences from the two tracking maps (easy, hard) at
# the three speeds, 3,300-12,700 frames each. Ours: whole laps of the route
# `loop`, (map, speed, laps) with the frames measured at 30 Hz (the first lap
# includes the start from rest); every (layout, speed) but easy at 6 m/s, both forms.
PAPER_PRESET = [
    ("tracking/easy_urban", 4.0, 2),    # 9,739 frames
    ("tracking/easy_desert", 8.0, 5),   # 12,182 frames
    ("tracking/hard_urban", 4.0, 1),    # 3,546 frames
    ("tracking/hard_desert", 6.0, 2),   # 4,712 frames
    ("tracking/hard_urban", 8.0, 3),    # 5,282 frames
]
LAP_FRAME_CAP = 20000  # a lap that takes longer than this many frames is an error

POSES_HEADER = ["frame", "frame_id", "sim_time", "uav_x", "uav_y", "uav_z", "uav_qw", "uav_qx", "uav_qy", "uav_qz",
                "target_x", "target_y", "target_z", "target_yaw_deg", "target_visibility", "target_visible_pixels",
                "cam_x", "cam_y", "cam_z", "cam_qw", "cam_qx", "cam_qy", "cam_qz"]
MEASURES_HEADER = ["frame", "in_view", "proj_x", "proj_y", "proj_w", "proj_h", "luma", "bc_similarity",
                   "sob_distance"]


class SequenceError(RuntimeError):
    pass


# ----------------------------------------------------------------------------- specs


def map_name(text):
    """'easy_urban', 'tracking/easy_urban' or a path -> 'tracking/easy_urban'."""
    text = text.strip()
    if text.endswith(".map"):
        text = text[:-4]
    if text.startswith("scenes/"):
        text = text[len("scenes/"):]
    return text if "/" in text else "tracking/" + text


def shipped_tracking_maps():
    paths = glob.glob(os.path.join(MAPS_DIR, "tracking", "*.map"))
    found = sorted("tracking/" + os.path.basename(p)[:-4] for p in paths)
    return found or list(TRACKING_MAPS)


def _speed_text(speed):
    return ("%g" % speed)


def sequence_name(map_, speed, conditions=None):
    name = "%s_s%s" % (map_.split("/")[-1], _speed_text(speed))
    if conditions and conditions != "clear_noon":
        name += "_" + conditions
    return name


class Spec:
    """One sequence to generate: frames > 0, or laps > 0 (then frames is a cap)."""

    def __init__(self, map_, speed, frames=0, laps=0, conditions=None, channels=(), seed=1, quality=None,
                 traffic_cars=0, name=None, camera_motion="pilot"):
        if (frames > 0) == (laps > 0):
            raise ValueError("give either frames or laps")
        self.map = map_name(map_)
        self.speed = float(speed)
        self.frames = int(frames)
        self.laps = int(laps)
        self.conditions = conditions
        self.channels = [c for c in EXTRA_CHANNELS if c in channels]
        self.seed = int(seed)
        self.quality = quality
        self.traffic_cars = int(traffic_cars)
        self.name = name or sequence_name(self.map, self.speed, conditions)
        if camera_motion not in CAMERA_MOTIONS:
            raise ValueError("camera_motion must be one of %s, not %r" % (", ".join(CAMERA_MOTIONS), camera_motion))
        self.camera_motion = camera_motion

    def settings(self):
        """What a complete sequence.json must match to be skipped on resume."""
        return {"map": self.map, "speed": self.speed, "requested_frames": self.frames,
                "requested_laps": self.laps, "conditions_requested": self.conditions,
                "channels": self.channels, "quality_requested": self.quality, "traffic_cars": self.traffic_cars,
                "camera_motion": self.camera_motion,
                "pilot_model": PILOT_MODEL if self.camera_motion == "pilot" else None}


def paper_specs(conditions=None, channels=(), seed=1):
    return [Spec(m, s, laps=l, conditions=conditions, channels=channels, seed=seed) for m, s, l in PAPER_PRESET]


# ----------------------------------------------------------------------------- the daemon


# ----------------------------------------------------------------------------- laps


class LapCounter:
    """Counts laps of a closed route from the car's poses: a lap ends when the
    car, having turned at least 2*pi*k - pi/2 in total (k = the lap), crosses the
    line through its start position square to its start heading, forwards,
    within 15 m of the start."""

    def __init__(self, radius=15.0):
        self.radius = radius
        self.start = None
        self.laps = 0
        self.turned = 0.0

    def update(self, x, y, yaw):
        if self.start is None:
            self.start = (x, y, yaw)
            self.prev = (x, y, yaw)
            return self.laps
        sx, sy, syaw = self.start
        px, py, pyaw = self.prev
        self.turned += (yaw - pyaw + math.pi) % (2 * math.pi) - math.pi

        def along(ax, ay):
            return (ax - sx) * math.cos(syaw) + (ay - sy) * math.sin(syaw)

        if (abs(self.turned) > 2 * math.pi * (self.laps + 1) - math.pi / 2 and along(px, py) < 0 <= along(x, y)
                and math.hypot(x - sx, y - sy) < self.radius):
            self.laps += 1
        self.prev = (x, y, yaw)
        return self.laps


# ----------------------------------------------------------------------------- one sequence


def _read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def _write_json(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def is_complete(seq_dir, spec=None):
    meta = _read_json(os.path.join(seq_dir, "sequence.json"))
    if not meta or not meta.get("complete"):
        return False
    if spec is not None:
        return all(meta.get(k) == v for k, v in spec.settings().items())
    return True


def _fields(message):
    return {f.name: v for f, v in message.ListFields()}


def _fmt(v):
    if isinstance(v, float):
        return "NaN" if math.isnan(v) else repr(round(v, 6)) if abs(v) < 1e15 else repr(v)
    return str(v)


def _write_csv(path, header, rows):
    with open(path, "w", encoding="utf-8") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            f.write(",".join(_fmt(v) for v in row) + "\n")


def _box_text(box):
    if box is None:
        return "NaN,NaN,NaN,NaN"
    return "%d,%d,%d,%d" % box


def _save_channel(seq_dir, channel, index, array):
    import cv2
    base = os.path.join(seq_dir, channel, "%06d" % index)
    if channel in ("mask", "semantic"):
        if not cv2.imwrite(base + ".png", np.ascontiguousarray(array)):
            raise SequenceError("cannot write %s.png" % base)
    else:
        np.save(base + ".npy", np.ascontiguousarray(array))


def _clear(seq_dir):
    for sub in ["img"] + list(EXTRA_CHANNELS):
        shutil.rmtree(os.path.join(seq_dir, sub), ignore_errors=True)
    for name in ("groundtruth_rect.txt", "poses.csv", "measures.csv", "pilot.csv", "attributes.txt",
                 "attributes_per_frame.csv", "sequence.json"):
        path = os.path.join(seq_dir, name)
        if os.path.exists(path):
            os.remove(path)


def generate_sequence(spec, out_root, daemon=None, frame_hook=None, log=None, progress_s=5.0):
    """Generates one sequence into out_root/spec.name (skipped if a complete
    sequence.json with the same settings is there; a partial one is
    regenerated). daemon: an address to use instead of starting sim4cvd.
    frame_hook(client, index, frame) is called after each frame is saved
    (tests use it to move the UAV). Returns the sequence.json dict, with
    "skipped": True when it was already complete."""
    import cv2
    import sim4cv

    log = log or (lambda text: print(text, flush=True))
    seq_dir = os.path.join(out_root, spec.name)
    if is_complete(seq_dir, spec):
        meta = _read_json(os.path.join(seq_dir, "sequence.json"))
        meta["skipped"] = True
        log("%s: complete (%d frames), skipped" % (spec.name, meta["frames"]))
        return meta
    if os.path.exists(seq_dir):
        log("%s: partial or different settings, regenerating" % spec.name)
        _clear(seq_dir)
    os.makedirs(os.path.join(seq_dir, "img"), exist_ok=True)
    for channel in spec.channels:
        os.makedirs(os.path.join(seq_dir, channel), exist_ok=True)

    own = None
    if daemon is None:
        args = ["--map", os.path.join(MAPS_DIR, spec.map + ".map"), "--car-speed", _speed_text(spec.speed),
                "--seed", str(spec.seed)]
        if spec.conditions:
            args += ["--conditions", spec.conditions]
        if spec.quality:
            args += ["--quality", spec.quality]
        if spec.traffic_cars:
            args += ["--traffic-cars", str(spec.traffic_cars)]
        own = OwnDaemon(args)  # lockstep
        address = own.address
    else:
        address = daemon if "://" in daemon else "tcp://" + daemon
    client = None
    try:
        client = sim4cv.connect(address, name="sim4cv.sequences", timeout=30.0)
        if own is None:
            traffic = {"cars": spec.traffic_cars} if spec.traffic_cars else None
            client.load_map_by_name(spec.map, car_speed=spec.speed, traffic=traffic)
            if spec.conditions or spec.quality:
                client.set_conditions(preset=spec.conditions or "", quality=spec.quality or "")
        world = client.get_world()
        welcome = client.welcome
        cars = [e for e in world.entities if e.kind == sim4cv.ENTITY_KIND_CAR]
        target = next((e for e in cars if e.name == "car"), cars[0] if cars else None)
        if target is None:
            raise SequenceError("%s: the world has no car to film" % spec.map)
        cameras = {c.name: c for c in world.cameras if c.name}
        if "uav" not in cameras:
            raise SequenceError("%s: no camera 'uav' (cameras: %s)" % (spec.map, ", ".join(cameras)))
        uav = next((e for e in world.entities if e.name == cameras["uav"].mounted_on), None)
        conditions = _fields(world.conditions) if world.HasField("conditions") else {}
        meta = {"name": spec.name, "complete": False, "format": "sim4cv-sequence 1",
                "map_name": world.scene_name, "route": world.routes[0] if world.routes else "",
                "conditions": conditions, "camera": "uav", "seed": spec.seed if own else None,
                "daemon": "own" if own else address, "daemon_version": welcome.server_version,
                "frame_hz": welcome.frame_hz, "physics_hz": welcome.physics_hz,
                "target_id": target.id, "target_name": target.name, "uav_id": uav.id if uav else None,
                "coordinates": "0-based pixels; box covers [x, x+w) x [y, y+h); NaN row: no visible pixel",
                "jpeg_quality": JPEG_QUALITY, "attribute_thresholds": attrs.THRESHOLDS,
                "sequence_min_fraction": attrs.SEQUENCE_MIN_FRACTION}
        meta.update(spec.settings())
        _write_json(os.path.join(seq_dir, "sequence.json"), meta)

        # The mask is always subscribed (it costs little): the attributes' luma and BC use the target's pixels.
        pilot, camera, pipeline = None, "uav", PIPELINE_STEPS
        if spec.camera_motion == "pilot":
            from .pilot import PILOT_HEADER, take_the_camera
            # one seed per (seed, sequence): the sequences of a set are flown differently, each the same every time
            pilot_seed = zlib.crc32(("%d:%s" % (spec.seed, spec.name)).encode())
            pilot = take_the_camera(client, world, target.id, pilot_seed, welcome.frame_hz, name=PILOT_CAMERA)
            camera, pipeline = PILOT_CAMERA, 1  # each frame's pose depends on the frame before
            meta.update(camera=camera, uav_id=None, pilot=pilot.description())
            uav = None  # removed: the camera columns of poses.csv hold the piloted pose
            _write_json(os.path.join(seq_dir, "sequence.json"), meta)
        pilot_rows = []
        client.subscribe(camera, ["rgb", "boxes"] + spec.channels + ([] if "mask" in spec.channels else ["mask"]),
                         "lockstep", with_state=True)
        cap = spec.frames if spec.frames else LAP_FRAME_CAP * spec.laps
        laps = LapCounter()
        gt_lines, poses, measures = [], [], []
        target_class = sim4cv.OBJECT_CLASS_CAR
        outstanding = 0
        t0 = last_report = time.monotonic()
        index = 0
        intrinsics = None
        while index < cap:
            while outstanding < min(pipeline, cap - index):
                client.step()
                outstanding += 1
            frame = client.receive_frame(timeout=60.0)
            outstanding -= 1
            index += 1
            msg = frame.message
            if intrinsics is None:
                ci = msg.camera_intrinsics
                intrinsics = {k: getattr(ci, k) for k in ("fx", "fy", "cx", "cy", "width", "height",
                                                          "k1", "k2", "p1", "p2", "k3")}
            rgb = frame.image("rgb")
            if not cv2.imwrite(os.path.join(seq_dir, "img", "%06d.jpg" % index), rgb[:, :, ::-1],
                               [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]):
                raise SequenceError("cannot write %s" % os.path.join(seq_dir, "img", "%06d.jpg" % index))
            for channel in spec.channels:
                _save_channel(seq_dir, channel, index, frame.image(channel))

            box = frame.box(target.id)
            visibility = float(box.visibility) if box else 0.0
            tbox = (box.x, box.y, box.width, box.height) if box and box.visibility > 0 else None
            gt_lines.append(_box_text(tbox))
            if box:
                target_class = box.object_class
            ents = {e.id: e for e in frame.entities}
            car = ents.get(target.id)
            drone = ents.get(uav.id) if uav else None
            nan3, nan4 = (math.nan,) * 3, (math.nan,) * 4
            cpos = car.position if car else nan3
            yaw = float(attrs.yaw_of(*car.orientation)) if car else math.nan
            cam = msg.camera_pose
            poses.append([index, frame.frame_id, frame.sim_time] + list(drone.position if drone else nan3)
                         + list(drone.orientation if drone else nan4) + list(cpos)
                         + [math.degrees(yaw), visibility, int(box.visible_pixels) if box else 0]
                         + [cam.position.x, cam.position.y, cam.position.z, cam.orientation.w, cam.orientation.x,
                            cam.orientation.y, cam.orientation.z])
            obj = next((o for o in msg.objects if o.object_id == target.id), None)
            proj = ((obj.projected_box.x, obj.projected_box.y, obj.projected_box.width, obj.projected_box.height)
                    if obj else nan4)
            luma, similarity = attrs.box_measures(rgb, tbox, frame.image("mask") == target.id)
            others = [(b.x, b.y, b.width, b.height) for b in frame.boxes
                      if b.object_id != target.id and b.object_class == target_class]
            sob = attrs.similar_object_distance(tbox, others)
            measures.append([index, 1 if obj is not None or box else 0] + list(proj) + [luma, similarity, sob])
            if pilot is not None:
                pilot_rows.append([index] + pilot.record())
            if spec.laps and car and laps.update(cpos[0], cpos[1], yaw) >= spec.laps:
                break
            if pilot is not None and index < cap:
                client.set_camera_pose(camera, *pilot.step(cpos, yaw, visibility))
            if frame_hook:
                frame_hook(client, index, frame)
            now = time.monotonic()
            if now - last_report >= progress_s:
                log("%s: %d%s frames, %.1f images/s" % (spec.name, index, "/%d" % spec.frames if spec.frames
                                                        else " (lap %d/%d)" % (laps.laps + 1, spec.laps),
                                                        index / (now - t0)))
                last_report = now
        else:
            if spec.laps:
                raise SequenceError("%s: %d laps not done in %d frames" % (spec.name, spec.laps, cap))
        elapsed = time.monotonic() - t0
    finally:
        if client is not None:
            client.close()
        if own is not None:
            own.stop()

    with open(os.path.join(seq_dir, "groundtruth_rect.txt"), "w", encoding="utf-8") as f:
        f.write("\n".join(gt_lines) + "\n")
    _write_csv(os.path.join(seq_dir, "poses.csv"), POSES_HEADER, poses)
    _write_csv(os.path.join(seq_dir, "measures.csv"), MEASURES_HEADER, measures)
    if pilot is not None:
        _write_csv(os.path.join(seq_dir, "pilot.csv"), ["frame"] + PILOT_HEADER, pilot_rows)
    meta.update({"frames": index, "laps_completed": laps.laps if spec.laps else None,
                 "camera_intrinsics": intrinsics, "image_size": [intrinsics["width"], intrinsics["height"]],
                 "generation_seconds": round(elapsed, 3), "images_per_second": round(index / max(elapsed, 1e-9), 2),
                 "target_absent_frames": sum(1 for line in gt_lines if line.startswith("NaN"))})
    _write_json(os.path.join(seq_dir, "sequence.json"), meta)  # attributes_of_sequence reads it
    flags = attrs.attributes_of_sequence(seq_dir)
    meta["attributes"] = {a: int(v) for a, v in attrs.write_attributes(seq_dir, flags).items()}
    meta["complete"] = True
    _write_json(os.path.join(seq_dir, "sequence.json"), meta)
    log("%s: %d frames in %.1f s, %.1f images/s; attributes %s" % (
        spec.name, index, elapsed, meta["images_per_second"],
        " ".join(a for a in attrs.ABBREVS if meta["attributes"][a]) or "none"))
    return meta


def _worker(args):
    spec, out_root, daemon = args
    return generate_sequence(spec, out_root, daemon)


def generate(specs, out_root, daemon=None, jobs=1, log=None):
    """Generates every spec (jobs at a time, each with its own daemon); writes
    out_root/attribute_names.txt. Returns the list of sequence.json dicts."""
    log = log or (lambda text: print(text, flush=True))
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise SequenceError("two sequences would be called the same: %s" % ", ".join(names))
    if daemon is not None and jobs > 1:
        raise SequenceError("--jobs > 1 needs own daemons (one world each); leave out --daemon")
    os.makedirs(out_root, exist_ok=True)
    attrs.write_attribute_names(out_root)
    t0 = time.monotonic()
    if jobs <= 1:
        results = [generate_sequence(s, out_root, daemon, log=log) for s in specs]
    else:
        with concurrent.futures.ProcessPoolExecutor(max_workers=jobs) as pool:
            results = list(pool.map(_worker, [(s, out_root, None) for s in specs]))
    made = [r for r in results if not r.get("skipped")]
    elapsed = time.monotonic() - t0
    images = sum(r["frames"] for r in made)
    log("%d sequences (%d generated, %d skipped): %d images in %.1f s, %.1f images/s overall"
        % (len(results), len(made), len(results) - len(made), images, elapsed, images / max(elapsed, 1e-9)))
    return results


def recompute_attributes(out_root, log=None):
    """Rewrites attribute_names.txt and every complete sequence's attribute files (e.g. after a threshold change)."""
    log = log or (lambda text: print(text, flush=True))
    attrs.write_attribute_names(out_root)
    for seq_dir in sorted(glob.glob(os.path.join(out_root, "*", "sequence.json"))):
        seq_dir = os.path.dirname(seq_dir)
        if is_complete(seq_dir):
            seq = attrs.write_attributes(seq_dir, attrs.attributes_of_sequence(seq_dir))
            log("%s: %s" % (os.path.basename(seq_dir), " ".join(a for a in attrs.ABBREVS if seq[a]) or "none"))



if __name__ == "__main__":
    from sim4cv.sequences_cli import main  # the command line lives there; this file is only its -m name
    sys.exit(main())
