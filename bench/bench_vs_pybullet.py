#!/usr/bin/python3
"""sim4cv's Python lockstep loop against pybullet DIRECT, side by side in one run.

    PYTHONPATH=/work/pybullet/site /usr/bin/python3 bench/bench_vs_pybullet.py [--frames 150] [--runs 3]

pybullet is built from source by bench/build_pybullet.sh (not packaged in Debian 12). Without
it the program still measures sim4cv (and says pybullet is missing).

Both sides run the same loop, one frame at a time, at 320x180 and 1280x720:
  sim4cv:   a sim4cvd of our own (lockstep, default look) serving the default scene (ground
            300 m square, road loop, 12 box buildings, a btRaycastVehicle car driving the loop,
            the UAV that follows it) with --walkers walkers spawned along the road and walking
            it; the Python client over shared memory: Step, wait for the frame (one frame = 1/30 s
            = 8 physics steps at 240 Hz, rendered from the UAV camera 15 m above the car, 60 deg
            down, 60 deg vertical field of view), take numpy views of RGB, depth and mask.
  pybullet: DIRECT mode in this process: 8 x stepSimulation (1/240 s), then getCameraImage
            (TinyRenderer: DIRECT has no GL) from the same camera placement, RGB, depth and
            segmentation mask as numpy arrays. Scene: pybullet_data's textured plane.urdf, the
            road as 48 flat boxes, the same 12 buildings as static boxes, a box car (1,200 kg
            chassis, four cylinder wheels on motorised revolute joints) driving at 6 m/s, the
            walkers as capsule bodies with a sphere head moved along the road at 1.4 m/s.
Reported per resolution: per-step wall time (median of each run, and the spread of those medians),
steps per second and the ratio. Then the full look against the flat look (--quality fast),
one daemon switched with SetConditions every --block frames, in one process; and four cameras
against one at 320x180 in one daemon (--only pybullet|flat|cameras runs one of the three).
"""

import argparse
import math
import os
import platform
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402

SIZES = ((320, 180), (1280, 720))
FRAME_HZ, PHYSICS_HZ = 30, 240
UAV_ALTITUDE, CAMERA_PITCH_DEG, FOV_Y_DEG = 15.0, 60.0, 60.0
WALKER_SPEED = 1.4
# The default scene's buildings (server/sim/default_scene.cpp): centre x, y, half x, half y, height, yaw.
BUILDINGS = ((-30, 0, 8, 10, 12, 0), (0, 0, 10, 8, 18, 0), (30, 0, 8, 10, 9, 0), (-20, -62, 8, 6, 14, 0),
             (20, -62, 10, 6, 10, 0), (75, -20, 6, 10, 16, 0), (75, 20, 6, 8, 8, 15), (20, 62, 10, 6, 20, 0),
             (-20, 62, 8, 6, 11, 0), (-75, 15, 6, 10, 13, 0), (-75, -25, 6, 8, 9, -10), (55, -60, 5, 5, 7, 30))


def road_loop():
    """The default scene's 48 road centre points: straights at y = -40, x = 60, y = 40 and x = -60
    (10 m apart) joined by 20 m arcs (15 degree steps), counter-clockwise from (-40, -40)."""
    points = []
    for (x0, y0, dx, dy), (cx, cy, a0) in zip(((-40, -40, 10, 0), (60, -20, 0, 10), (40, 40, -10, 0),
                                               (-60, 20, 0, -10)),
                                              ((40, -20, -90), (40, 20, 0), (-40, 20, 90), (-40, -20, 180))):
        points += [(x0 + k * dx, y0 + k * dy) for k in range(9 if dx else 5)]
        points += [(cx + 20 * math.cos(math.radians(a0 + 15 * k)), cy + 20 * math.sin(math.radians(a0 + 15 * k)))
                   for k in range(1, 6)]
    return points


def walker_starts(count):
    """Walkers on the south sidewalk ahead of the car (y = -46), spread over 60 m."""
    return [(-38.0 + 60.0 * i / max(1, count), -46.0 - (i % 2)) for i in range(count)]


def spread(values):
    return "%.2f-%.2f" % (min(values), max(values))


# --- sim4cv -----------------------------------------------------------------------------------
def start_sim4cv(width, height, walkers, extra=()):
    name = "/s4cv-vs-pyb-%d-%d" % (os.getpid(), width)
    daemon = OwnDaemon(["--shm-name", name, "--width", str(width), "--height", str(height),
                        "--log-level", "warning"] + list(extra))
    client = sim4cv.connect("shm://" + daemon.fields["shm"], name="bench-vs-pybullet")
    for i, (x, y) in enumerate(walker_starts(walkers)):
        walker = client.spawn("pedestrian", "walker%d" % i, x, y, 0.0, yaw_deg=0.0)
        client.set_waypoints(walker, [(x, y), (x + 80.0, y)], False, WALKER_SPEED)
    client.subscribe(client.ring_geometry.camera_name, ["rgb", "depth", "mask"], "lockstep")
    return daemon, client


def sim4cv_steps(client, frames):
    """Per-step wall times (s) of `frames` lockstep steps, each frame's planes taken as numpy."""
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        frame = client.step_and_receive()
        frame.image("rgb"), frame.image("depth"), frame.image("mask")
        times.append(time.perf_counter() - t)
    return times


# --- pybullet ---------------------------------------------------------------------------------
class PybulletScene:
    """The mirror scene in a DIRECT pybullet (see the module doc)."""

    def __init__(self, pybullet, pybullet_data, width, height, walkers):
        p = self.p = pybullet
        self.cid = p.connect(p.DIRECT)
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=self.cid)
        p.setGravity(0, 0, -9.81, physicsClientId=self.cid)
        p.setTimeStep(1.0 / PHYSICS_HZ, physicsClientId=self.cid)
        p.loadURDF("plane.urdf", globalScaling=1.5, physicsClientId=self.cid)  # 300 m square like ours
        points = road_loop()
        for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1]):
            length = math.hypot(x1 - x0, y1 - y0)
            self.box((length / 2 + 0.5, 4.0, 0.01), ((x0 + x1) / 2, (y0 + y1) / 2, 0.01),
                     math.atan2(y1 - y0, x1 - x0), (0.25, 0.25, 0.27, 1), collide=False)
        for cx, cy, hx, hy, h, yaw in BUILDINGS:
            self.box((hx, hy, h / 2), (cx, cy, h / 2), math.radians(yaw), (0.7, 0.62, 0.55, 1))
        self.car = self.make_car()
        self.walkers = [self.make_walker(x, y) for x, y in walker_starts(walkers)]
        self.walker_starts = walker_starts(walkers)
        self.step_count = 0
        self.width, self.height = width, height
        self.projection = p.computeProjectionMatrixFOV(FOV_Y_DEG, width / height, 0.1, 500.0)

    def box(self, half, position, yaw, colour, collide=True):
        p = self.p
        visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=colour, physicsClientId=self.cid)
        collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.cid) if collide else -1
        return p.createMultiBody(0, collision, visual, position, p.getQuaternionFromEuler((0, 0, yaw)),
                                 physicsClientId=self.cid)

    def make_car(self):
        p, cid = self.p, self.cid
        chassis_v = p.createVisualShape(p.GEOM_BOX, halfExtents=(2.25, 0.9, 0.5), rgbaColor=(0.8, 0.1, 0.1, 1),
                                        physicsClientId=cid)
        chassis_c = p.createCollisionShape(p.GEOM_BOX, halfExtents=(2.25, 0.9, 0.5), physicsClientId=cid)
        wheel_v = p.createVisualShape(p.GEOM_CYLINDER, radius=0.35, length=0.25, rgbaColor=(0.1, 0.1, 0.1, 1),
                                      physicsClientId=cid)
        wheel_c = p.createCollisionShape(p.GEOM_CYLINDER, radius=0.35, height=0.25, physicsClientId=cid)
        axle = p.getQuaternionFromEuler((math.pi / 2, 0, 0))  # cylinder axis (z) along the car's y
        wheels = [(1.4, 0.95), (1.4, -0.95), (-1.4, 0.95), (-1.4, -0.95)]
        car = p.createMultiBody(
            1200, chassis_c, chassis_v, (-40.0, -42.0, 0.9), (0, 0, 0, 1),
            linkMasses=[20] * 4, linkCollisionShapeIndices=[wheel_c] * 4, linkVisualShapeIndices=[wheel_v] * 4,
            linkPositions=[(x, y, -0.55) for x, y in wheels], linkOrientations=[axle] * 4,
            linkInertialFramePositions=[(0, 0, 0)] * 4, linkInertialFrameOrientations=[(0, 0, 0, 1)] * 4,
            linkParentIndices=[0] * 4, linkJointTypes=[p.JOINT_REVOLUTE] * 4, linkJointAxis=[(0, 0, 1)] * 4,
            physicsClientId=cid)
        # Wheel spin about the cylinder axis; forward (+x) needs a negative rate about +y = axle z.
        p.setJointMotorControlArray(car, range(4), p.VELOCITY_CONTROL, targetVelocities=[-6.0 / 0.35] * 4,
                                    forces=[800] * 4, physicsClientId=cid)
        return car

    def make_walker(self, x, y):
        p, cid = self.p, self.cid
        body = p.createVisualShape(p.GEOM_CAPSULE, radius=0.25, length=1.1, rgbaColor=(0.2, 0.3, 0.6, 1),
                                   physicsClientId=cid)
        head_v = p.createVisualShape(p.GEOM_SPHERE, radius=0.12, rgbaColor=(0.9, 0.7, 0.6, 1), physicsClientId=cid)
        collision = p.createCollisionShape(p.GEOM_CAPSULE, radius=0.25, height=1.1, physicsClientId=cid)
        return p.createMultiBody(0, collision, body, (x, y, 0.8), (0, 0, 0, 1), linkMasses=[0],
                                 linkCollisionShapeIndices=[-1], linkVisualShapeIndices=[head_v],
                                 linkPositions=[(0, 0, 0.95)], linkOrientations=[(0, 0, 0, 1)],
                                 linkInertialFramePositions=[(0, 0, 0)], linkInertialFrameOrientations=[(0, 0, 0, 1)],
                                 linkParentIndices=[0], linkJointTypes=[p.JOINT_FIXED], linkJointAxis=[(0, 0, 1)],
                                 physicsClientId=cid)

    def step(self):
        """One frame: 8 physics steps with the walkers moved, then the camera image."""
        p, cid = self.p, self.cid
        for _ in range(PHYSICS_HZ // FRAME_HZ):
            self.step_count += 1
            walked = WALKER_SPEED * self.step_count / PHYSICS_HZ
            for walker, (x, y) in zip(self.walkers, self.walker_starts):
                p.resetBasePositionAndOrientation(walker, (x + walked, y, 0.8), (0, 0, 0, 1), physicsClientId=cid)
            p.stepSimulation(physicsClientId=cid)
        (cx, cy, cz), orientation = p.getBasePositionAndOrientation(self.car, physicsClientId=cid)
        yaw = p.getEulerFromQuaternion(orientation)[2]
        back = UAV_ALTITUDE / math.tan(math.radians(CAMERA_PITCH_DEG))
        eye = (cx - back * math.cos(yaw), cy - back * math.sin(yaw), cz + UAV_ALTITUDE)
        view = p.computeViewMatrix(eye, (cx, cy, cz), (0, 0, 1))
        return p.getCameraImage(self.width, self.height, view, self.projection, renderer=p.ER_TINY_RENDERER,
                                physicsClientId=cid)

    def close(self):
        self.p.disconnect(physicsClientId=self.cid)


def pybullet_steps(scene, frames):
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        _, _, rgb, depth, mask = scene.step()
        times.append(time.perf_counter() - t)
    return times, (rgb, depth, mask)


def load_pybullet():
    try:
        import pybullet
        import pybullet_data
    except ImportError as e:
        return None, None, str(e)
    return pybullet, pybullet_data, None


# --- the comparisons --------------------------------------------------------------------------
def side_by_side(args, pybullet, pybullet_data):
    rows = []
    for width, height in SIZES:
        frames = args.frames if width <= 640 else max(30, args.frames // 3)
        ours, theirs = [], []
        for run in range(args.runs):
            daemon, client = start_sim4cv(width, height, args.walkers)
            try:
                sim4cv_steps(client, args.warmup)
                ours.append(statistics.median(sim4cv_steps(client, frames)))
            finally:
                client.close()
                daemon.stop()
            if pybullet is not None:
                scene = PybulletScene(pybullet, pybullet_data, width, height, args.walkers)
                try:
                    pybullet_steps(scene, args.warmup)
                    times, images = pybullet_steps(scene, frames)
                    theirs.append(statistics.median(times))
                    if run == 0:
                        check_pybullet_images(images, width, height)
                finally:
                    scene.close()
            print("  %dx%d run %d: sim4cv %.2f ms, pybullet %s" % (
                width, height, run + 1, ours[-1] * 1e3, "%.2f ms" % (theirs[-1] * 1e3) if theirs else "-"),
                file=sys.stderr)
        rows.append((width, height, frames, ours, theirs))
    return rows


def check_pybullet_images(images, width, height):
    """pybullet's images are what we asked for and show the scene (not an empty frame)."""
    rgb, depth, mask = images
    import numpy as np
    rgb, mask = np.asarray(rgb), np.asarray(mask)
    assert rgb.shape[:2] == (height, width), rgb.shape
    assert len(np.unique(mask)) >= 3, "pybullet's mask shows fewer than three objects: the camera misses the scene"


def full_against_flat(args):
    rows = []
    for width, height in SIZES:
        frames = args.frames if width <= 640 else max(30, args.frames // 3)
        daemon, client = start_sim4cv(width, height, args.walkers)
        times = {"full": [], "fast": []}
        try:
            sim4cv_steps(client, args.warmup)
            done = 0
            while done < frames * args.runs:
                for quality in ("fast", "full"):
                    client.set_conditions(quality=quality)
                    client.step_and_receive()  # the first frame after the switch is not timed
                    times[quality] += sim4cv_steps(client, args.block)
                done += args.block
        finally:
            client.close()
            daemon.stop()
        rows.append((width, height, times))
    return rows


def four_against_one(args):
    """Per-step wall time with one camera (the shm client's) and with four (plus car_front,
    car_chase and a camera added on the UAV looking 45 deg down, each subscribed by a Python TCP
    client to RGB, depth and mask in lockstep), alternating in one daemon at 320x180."""
    daemon, client = start_sim4cv(320, 180, args.walkers)
    times = {1: [], 4: []}
    try:
        client.add_camera("uav_45", mounted_on="uav", pitch_down_deg=45.0, gimbal=True)
        address = "tcp://127.0.0.1:%s" % daemon.fields["tcp"]
        sim4cv_steps(client, args.warmup)
        for _ in range(args.runs):
            times[1] += sim4cv_steps(client, args.frames)
            others = []
            try:
                for camera in ("car_front", "car_chase", "uav_45"):
                    others.append(sim4cv.connect(address, name="bench-" + camera))
                    others[-1].subscribe(camera, ["rgb", "depth", "mask"], "lockstep")
                everyone = [client] + others
                for k in range(args.warmup + args.frames):
                    t = time.perf_counter()
                    for c in everyone:
                        c.step()
                    for c in everyone:
                        frame = c.receive_frame()
                        frame.image("rgb"), frame.image("depth"), frame.image("mask")
                    if k >= args.warmup:
                        times[4].append(time.perf_counter() - t)
            finally:
                for c in others:
                    c.close()
    finally:
        client.close()
        daemon.stop()
    return times


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=150, help="timed frames per run at 320x180 (a third at 1280x720)")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--warmup", type=int, default=10)
    p.add_argument("--walkers", type=int, default=10)
    p.add_argument("--block", type=int, default=10, help="frames per look before switching (full against flat)")
    p.add_argument("--only", choices=("pybullet", "flat", "cameras"), help="one comparison only")
    args = p.parse_args()
    started = time.monotonic()
    pybullet, pybullet_data, missing = load_pybullet()
    print("machine: %s, %d cores, load average %s; python %s; pybullet %s" % (
        platform.processor() or platform.machine(), os.cpu_count(), " ".join("%.2f" % x for x in os.getloadavg()),
        platform.python_version(), "API %d, numpy %s" % (pybullet.getAPIVersion(), bool(pybullet.isNumpyEnabled()))
        if pybullet else "missing (%s)" % missing))
    if args.only in (None, "pybullet"):
        print_side_by_side(args, pybullet, pybullet_data)
    if args.only in (None, "flat"):
        print("\n| size | flat look (--quality fast) step | full look (default) step | full / flat |\n|---|---|---|---|")
        for width, height, times in full_against_flat(args):
            fast, full = statistics.median(times["fast"]), statistics.median(times["full"])
            print("| %dx%d (%d frames each, blocks of %d) | %.2f ms | %.2f ms | %.2fx |" % (
                width, height, len(times["full"]), args.block, fast * 1e3, full * 1e3, full / fast))
    if args.only in (None, "cameras"):
        times = four_against_one(args)
        one, four = statistics.median(times[1]), statistics.median(times[4])
        print("\n| 320x180, RGB + depth + mask | one camera (shm) | four cameras (shm + 3 TCP) | four / one |\n"
              "|---|---|---|---|\n| step, median of %d frames each | %.2f ms | %.2f ms | %.2fx |"
              % (len(times[1]), one * 1e3, four * 1e3, four / one))
    print("\n(%.0f s; load average at the end %s)" % (time.monotonic() - started,
                                                     " ".join("%.2f" % x for x in os.getloadavg())))


def print_side_by_side(args, pybullet, pybullet_data):
    print("\n| size | sim4cv step, median of runs (spread) | sim4cv steps/s | pybullet step (spread) | "
          "pybullet steps/s | sim4cv / pybullet speed |\n|---|---|---|---|---|---|")
    for width, height, frames, ours, theirs in side_by_side(args, pybullet, pybullet_data):
        mo = statistics.median(ours)
        cells = ["%dx%d (%d frames x %d runs)" % (width, height, frames, len(ours)),
                 "%.2f ms (%s)" % (mo * 1e3, spread([x * 1e3 for x in ours])), "%.0f" % (1 / mo)]
        if theirs:
            mt = statistics.median(theirs)
            cells += ["%.2f ms (%s)" % (mt * 1e3, spread([x * 1e3 for x in theirs])), "%.0f" % (1 / mt),
                      "%.1fx (runs %s)" % (mt / mo, spread([t / o for t, o in zip(theirs, ours)]))]
        else:
            cells += ["-", "-", "-"]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
