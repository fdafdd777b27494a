#!/usr/bin/python3
"""sim4cv's Python lockstep loop against pybullet DIRECT, side by side in one run.

    PYTHONPATH=/work/pybullet/site /usr/bin/python3 bench/bench_vs_pybullet.py [--frames 150] [--runs 3]

pybullet is built from source by bench/build_pybullet.sh (not packaged in Debian 12). Without
it the program still measures sim4cv (and says pybullet is missing).

Both sides run the same loop, one frame at a time, at 320x180 and 1280x720:
  sim4cv:   a sim4cvd of our own (lockstep, default look: --quality full, clear_noon, sun
            shadows) serving the default scene (ground, road loop, 12 buildings, a car driving
            the loop, the camera UAV following it) with --walkers walkers spawned on the
            sidewalk ahead of the car and walking it; the Python client over shared memory:
            Step, wait for the frame (1/30 s = 8 physics steps at 240 Hz, rendered from the UAV
            camera 15 m above the car, 60 deg down, 60 deg vertical field of view, boxes
            extracted), take numpy views of RGB, depth and mask.
  pybullet: bench/pybullet_scene.py in this process: the same content and camera,
            8 x stepSimulation + getCameraImage (TinyRenderer), RGB, depth and mask as numpy.
Each run starts both and alternates them in blocks of --block frames, so that the machine's
load drifts over both alike. Reported per resolution: per-step wall time (median of each run's
steps, median and spread over runs), steps per second, CPU time per step (sim4cv: daemon and
client processes together; pybullet: this process) and the ratios.
Then (--only runs one part): the full look against the flat look (--quality fast), one daemon
switched with SetConditions every --block frames; and four cameras against one at 320x180.
"""

import argparse
import os
import platform
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "clients", "python"))
sys.path.insert(0, HERE)

import sim4cv  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402
from pybullet_scene import WALKER_SPEED, PybulletScene, walker_starts  # noqa: E402

SIZES = ((320, 180), (1280, 720))
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def spread(values):
    return "%.2f-%.2f" % (min(values), max(values))


def process_cpu_seconds(pid):
    """User + system CPU time of every thread of process `pid` so far."""
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


class Meter:
    """Wall time per step and CPU time of blocks of steps, summed over blocks."""

    def __init__(self, daemon_pid=None):
        self.daemon_pid = daemon_pid
        self.times, self.cpu, self.daemon_cpu = [], 0.0, 0.0

    def block(self, step, count):
        client_start = time.process_time()
        daemon_start = process_cpu_seconds(self.daemon_pid) if self.daemon_pid else 0.0
        for _ in range(count):
            t = time.perf_counter()
            step()
            self.times.append(time.perf_counter() - t)
        daemon = (process_cpu_seconds(self.daemon_pid) - daemon_start) if self.daemon_pid else 0.0
        self.daemon_cpu += daemon
        self.cpu += time.process_time() - client_start + daemon

    def median_s(self):
        return statistics.median(self.times)

    def cpu_per_step_s(self):
        return self.cpu / len(self.times)


# --- sim4cv -----------------------------------------------------------------------------------
def start_sim4cv(width, height, walkers, extra=()):
    name = "/s4cv-vs-pyb-%d-%d" % (os.getpid(), time.monotonic_ns() % 1000000)
    # A long expiry: the client sends nothing while pybullet takes its turn (seconds at 1280x720).
    daemon = OwnDaemon(["--shm-name", name, "--shm-expiry-ms", "120000", "--width", str(width), "--height",
                        str(height), "--log-level", "warning"] + list(extra))
    try:
        client = sim4cv.connect("shm://" + daemon.fields["shm"], name="bench-vs-pybullet")
        for i, (x, y) in enumerate(walker_starts(walkers)):
            walker = client.spawn("pedestrian", "walker%d" % i, x, y, 0.0)
            client.set_waypoints(walker, [(x, y), (x + 80.0, y)], False, WALKER_SPEED)
        client.subscribe(client.ring_geometry.camera_name, ["rgb", "depth", "mask"], "lockstep")
    except BaseException:
        daemon.stop()
        raise
    return daemon, client


def sim4cv_step(client):
    """One lockstep step, the frame's planes taken as numpy (zero-copy views of the ring)."""
    frame = client.step_and_receive()
    frame.image("rgb"), frame.image("depth"), frame.image("mask")


def sim4cv_warm(client, frames):
    for _ in range(frames):
        sim4cv_step(client)


# --- the comparisons --------------------------------------------------------------------------
def frames_for(args, width):
    return args.frames if width <= 640 else max(30, args.frames // 3)


def side_by_side(args, pybullet, pybullet_data):
    """Per size: a list per run of (sim4cv Meter, pybullet Meter or None)."""
    results = []
    for width, height in SIZES:
        frames, runs = frames_for(args, width), []
        for run in range(args.runs):
            daemon, client = start_sim4cv(width, height, args.walkers)
            scene = PybulletScene(pybullet, pybullet_data, width, height, args.walkers) if pybullet else None
            ours, theirs = Meter(daemon.proc.pid), Meter() if scene else None
            try:
                sim4cv_warm(client, args.warmup)
                if scene:
                    for _ in range(args.warmup):
                        scene.step()
                    scene.check_image(*scene.step())
                while len(ours.times) < frames:
                    count = min(args.block, frames - len(ours.times))
                    ours.block(lambda: sim4cv_step(client), count)
                    if scene:
                        theirs.block(scene.step, count)
            finally:
                client.close()
                daemon.stop()
                if scene:
                    scene.close()
            runs.append((ours, theirs))
            print("  %dx%d run %d: sim4cv %.2f ms (cpu %.2f), pybullet %s" % (
                width, height, run + 1, ours.median_s() * 1e3, ours.cpu_per_step_s() * 1e3,
                "%.2f ms (cpu %.2f)" % (theirs.median_s() * 1e3, theirs.cpu_per_step_s() * 1e3) if theirs else "-"),
                file=sys.stderr)
        results.append((width, height, frames, runs))
    return results


def print_side_by_side(results):
    print("\n| size | sim4cv step: median (spread of run medians) | steps/s | CPU per step | "
          "pybullet step | steps/s | CPU per step | wall-time ratio (runs) | CPU ratio |\n" + "|---" * 9 + "|")
    for width, height, frames, runs in results:
        ours = [o.median_s() * 1e3 for o, _ in runs]
        ours_cpu = [o.cpu_per_step_s() * 1e3 for o, _ in runs]
        mo, co = statistics.median(ours), statistics.median(ours_cpu)
        cells = ["%dx%d (%d frames x %d runs)" % (width, height, frames, len(runs)),
                 "%.2f ms (%s)" % (mo, spread(ours)), "%.0f" % (1e3 / mo), "%.2f ms" % co]
        if runs[0][1] is not None:
            theirs = [t.median_s() * 1e3 for _, t in runs]
            theirs_cpu = [t.cpu_per_step_s() * 1e3 for _, t in runs]
            mt, ct = statistics.median(theirs), statistics.median(theirs_cpu)
            cells += ["%.2f ms (%s)" % (mt, spread(theirs)), "%.1f" % (1e3 / mt), "%.2f ms" % ct,
                      "**%.1fx** (%s)" % (mt / mo, spread([t / o for t, o in zip(theirs, ours)])), "%.1fx" % (ct / co)]
        else:
            cells += ["-"] * 5
        print("| " + " | ".join(cells) + " |")


def full_against_flat(args):
    print("\n| size | flat look (--quality fast): step, CPU | full look (default): step, CPU | full / flat: wall, CPU |\n"
          "|---|---|---|---|")
    for width, height in SIZES:
        frames = frames_for(args, width) * args.runs
        daemon, client = start_sim4cv(width, height, args.walkers)
        meters = {"fast": Meter(daemon.proc.pid), "full": Meter(daemon.proc.pid)}
        try:
            sim4cv_warm(client, args.warmup)
            while len(meters["full"].times) < frames:
                for quality, meter in meters.items():
                    client.set_conditions(quality=quality)
                    sim4cv_step(client)  # the first frame after the switch is not timed
                    meter.block(lambda: sim4cv_step(client), args.block)
        finally:
            client.close()
            daemon.stop()
        fast, full = meters["fast"], meters["full"]
        print("| %dx%d (%d frames each, blocks of %d) | %.2f ms, %.2f ms | %.2f ms, %.2f ms | **%.2fx**, %.2fx |" % (
            width, height, len(full.times), args.block, fast.median_s() * 1e3, fast.cpu_per_step_s() * 1e3,
            full.median_s() * 1e3, full.cpu_per_step_s() * 1e3, full.median_s() / fast.median_s(),
            full.cpu_per_step_s() / fast.cpu_per_step_s()))


# Three cameras added to the shm client's one (the UAV's): a surround rig on the UAV (the same
# view turned 90, 180 and 270 deg: as much scene per camera as the first), and a mixed set (the
# car's two cameras, which see the horizon and sky, and one on the UAV looking 45 deg down).
CAMERA_SETS = {
    "surround rig": [("uav_%d" % yaw, dict(mounted_on="uav", pitch_down_deg=60.0, yaw_deg=yaw, gimbal=True))
                     for yaw in (90, 180, 270)],
    "mixed": [("car_front", None), ("car_chase", None),
              ("uav_45", dict(mounted_on="uav", pitch_down_deg=45.0, gimbal=True))],
}


def four_against_one(args):
    """Per camera set: one camera (the shm client's) against four (the three more each subscribed
    by a Python TCP client to RGB, depth and mask in lockstep), alternating in blocks in one
    daemon at 320x180."""
    print("\n| 320x180, RGB + depth + mask, lockstep | one camera (shm): step, CPU (daemon's) | four cameras (shm + "
          "3 TCP): step, CPU (daemon's) | four / one: wall, CPU, daemon's CPU |\n|---|---|---|---|")
    for set_name, cameras in CAMERA_SETS.items():
        daemon, client = start_sim4cv(320, 180, args.walkers)
        meters = {1: Meter(daemon.proc.pid), 4: Meter(daemon.proc.pid)}
        try:
            for name, spec in cameras:
                if spec is not None:
                    client.add_camera(name, **spec)
            address = "tcp://127.0.0.1:%s" % daemon.fields["tcp"]
            sim4cv_warm(client, args.warmup)
            while len(meters[4].times) < frames_for(args, 320) * args.runs:
                meters[1].block(lambda: sim4cv_step(client), args.block)
                # Three more lockstep subscribers for this block only (closing them ends their cameras' renders).
                others = []
                try:
                    for name, _ in cameras:
                        others.append(sim4cv.connect(address, name="bench-" + name))
                        others[-1].subscribe(name, ["rgb", "depth", "mask"], "lockstep")
                    everyone = [client] + others

                    def step_all():
                        for c in everyone:
                            c.step()
                        for c in everyone:
                            frame = c.receive_frame()
                            frame.image("rgb"), frame.image("depth"), frame.image("mask")
                    step_all()  # the first step with four cameras is not timed
                    meters[4].block(step_all, args.block)
                finally:
                    for c in others:
                        c.close()
        finally:
            client.close()
            daemon.stop()
        one, four = meters[1], meters[4]
        print("| %s (%s), %d frames each | %.2f ms, %.2f ms (%.2f) | %.2f ms, %.2f ms (%.2f) | **%.2fx**, %.2fx, %.2fx |"
              % (set_name, ", ".join(name for name, _ in cameras), len(four.times), one.median_s() * 1e3,
                 one.cpu_per_step_s() * 1e3, one.daemon_cpu / len(one.times) * 1e3, four.median_s() * 1e3,
                 four.cpu_per_step_s() * 1e3, four.daemon_cpu / len(four.times) * 1e3,
                 four.median_s() / one.median_s(), four.cpu_per_step_s() / one.cpu_per_step_s(),
                 four.daemon_cpu / one.daemon_cpu * len(one.times) / len(four.times)))


def load_pybullet():
    try:
        import pybullet
        import pybullet_data
    except ImportError as e:
        return None, None, str(e)
    return pybullet, pybullet_data, None


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=150, help="timed frames per run at 320x180 (a third at 1280x720)")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--warmup", type=int, default=10)
    p.add_argument("--walkers", type=int, default=10)
    p.add_argument("--block", type=int, default=10, help="frames per side (or look, or camera count) in turn")
    p.add_argument("--only", choices=("pybullet", "flat", "cameras"), help="one comparison only")
    args = p.parse_args()
    started = time.monotonic()
    pybullet, pybullet_data, missing = load_pybullet()
    print("%s: %s, %d cores, load average %s; python %s; pybullet %s" % (
        time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), platform.processor() or platform.machine(),
        os.cpu_count(), " ".join("%.2f" % x for x in os.getloadavg()), platform.python_version(),
        "API %d, numpy %s" % (pybullet.getAPIVersion(), bool(pybullet.isNumpyEnabled()))
        if pybullet else "missing (%s)" % missing))
    if args.only in (None, "pybullet"):
        print_side_by_side(side_by_side(args, pybullet, pybullet_data))
    if args.only in (None, "flat"):
        full_against_flat(args)
    if args.only in (None, "cameras"):
        four_against_one(args)
    print("\n(%.0f s; load average at the end %s)" % (time.monotonic() - started,
                                                     " ".join("%.2f" % x for x in os.getloadavg())))


if __name__ == "__main__":
    main()
