"""Throughput of a study run as tasks (docs/scaling.md, "Measured"): an
online sweep of 8 lockstep runs (4 speeds x gt and KCF, 5 s of sim time at
30 fps) with the local executor at 1 and 2 tasks at a time, repeated; the
per-task overhead (sim4cvd start with its map load; a run-one process that
only finds its task done); optionally the same sweep as a Slurm array on a
one-machine cluster (tests/python/local_slurm.py).

    SIM4CVD=build/server/daemon/sim4cvd /usr/bin/python3 bench/bench_scaling.py [--repeat 3] [--slurm]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))
sys.path.insert(0, os.path.join(REPO_ROOT, "tests", "python"))
ENV = dict(os.environ, PYTHONPATH=os.path.join(REPO_ROOT, "clients", "python"))
SWEEP = """kind: online
maps: [tracking/easy_urban]
speeds: [4, 6, 8, 10]
trackers: [gt, "opencv:kcf"]
modes: [lockstep]
seconds: 5
"""


def cli(*args, env=None):
    proc = subprocess.run([sys.executable, "-m", "sim4cv.experiment"] + [str(a) for a in args], cwd=REPO_ROOT,
                          env=env or ENV, capture_output=True, text=True)
    if proc.returncode not in (0, 1):
        raise SystemExit(proc.stderr)
    return proc


def frames(out):
    records = json.load(open(os.path.join(out, "results.json")))
    return sum(r["frames_processed"] + r["frames_skipped"] for r in records if r["uav"] == 0), len(records)


def spread(values):
    return "%.2f (min %.2f, max %.2f, n=%d)" % (statistics.median(values), min(values), max(values), len(values))


def sweep(tmp, jobs, submit):
    out = tempfile.mkdtemp(dir=tmp)
    path = os.path.join(tmp, "sweep.yaml")
    t0 = time.monotonic()
    submit(path, out, jobs)
    wall = time.monotonic() - t0
    n_frames, n_tasks = frames(out)
    return 60.0 * n_tasks / wall, n_frames / wall, wall


def local(path, out, jobs):
    cli("run", path, "--out", out, "--jobs", jobs)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--slurm", action="store_true")
    args = p.parse_args()
    from sim4cv.daemon import OwnDaemon
    tmp = tempfile.mkdtemp(prefix="bench-scaling-")
    with open(os.path.join(tmp, "sweep.yaml"), "w") as f:
        f.write(SWEEP)
    print("machine: %d cores (nproc); load average at start %s" % (len(os.sched_getaffinity(0)),
                                                                   open("/proc/loadavg").read().split()[:3]))
    starts = []
    for _ in range(args.repeat + 2):
        t0 = time.monotonic()
        with OwnDaemon(["--map", os.path.join(REPO_ROOT, "scenes", "tracking", "easy_urban.map")]):
            starts.append(time.monotonic() - t0)
    print("sim4cvd start to listening (map loaded), s: %s" % spread(starts))
    for jobs in (1, 2):
        results = [sweep(tmp, jobs, local) for _ in range(args.repeat)]
        print("local --jobs %d: tasks/min %s; daemon-frames/s %s; wall s %s" % (
            jobs, spread([r[0] for r in results]), spread([r[1] for r in results]), spread([r[2] for r in results])))
    done = tempfile.mkdtemp(dir=tmp)
    cli("run", os.path.join(tmp, "sweep.yaml"), "--out", done, "--jobs", 2)
    skips = []
    for i in range(args.repeat + 2):
        t0 = time.monotonic()
        cli("run-one", done, "--index", i)
        skips.append(time.monotonic() - t0)
    print("run-one of a task already done (python start, plan read), s: %s" % spread(skips))
    if args.slurm:
        from local_slurm import LocalSlurm
        with LocalSlurm(cpus=2) as slurm:
            env = dict(ENV, SLURM_CONF=slurm.conf, PATH=slurm.env["PATH"])

            def on_slurm(path, out, jobs):
                cli("run", path, "--out", out, "--jobs", jobs, "--executor", "slurm", "--wait", env=env)

            for jobs in (1, 2):
                results = [sweep(tmp, jobs, on_slurm) for _ in range(args.repeat)]
                print("slurm --jobs %d (array %%%d, gather job included): tasks/min %s; daemon-frames/s %s; wall s %s"
                      % (jobs, jobs, spread([r[0] for r in results]), spread([r[1] for r in results]),
                         spread([r[2] for r in results])))
    print("load average at end %s" % open("/proc/loadavg").read().split()[:3])


if __name__ == "__main__":
    main()
