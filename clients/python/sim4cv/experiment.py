"""Scripted experiments: a YAML file names a grid of online tracking runs
(sim4cv.tracking) or an offline OPE study (sim4cv.sequences + sim4cv.ope);
this runs every combination, resumes, and writes tables, plots and a report.

    python3 -m sim4cv.experiment run FILE.yaml --out DIR [--executor local|slurm|dask] [--jobs J] [--daemon ADDRESS]
    python3 -m sim4cv.experiment plan|run-one|status|gather|resubmit ...   (docs/scaling.md)

docs/tracking.md, "Experiments", lists every key with its default. The file
is checked as a whole (unknown keys, tracker specifications, maps, modes)
before any run starts. Online: each run is DIR/runs/<name from its
parameters>/ (session.json, run.s4log, frames_<k>.csv); a run whose
session.json exists is skipped, any other is redone from scratch. Offline:
DIR/results/<tracker>/<seq>.txt per tracker and sequence (skipped if present),
then DIR/ope/. Both end with DIR/results.json, results.csv, plots/ and report.md
(sim4cv.experiment_report).
"""

import bisect
import csv
import json
import math
import multiprocessing
import os
import re
import shutil
import sys
import time

from .daemon import REPO_ROOT

ONLINE_DEFAULTS = {
    "kind": "online", "name": "", "maps": ["tracking/easy_urban"], "speeds": [6.0], "trackers": ["gt"],
    "modes": ["lockstep"], "fps": [30.0], "delays_ms": [0.0], "conditions": [""], "repetitions": 1,
    "seconds": 60.0, "uavs_per_run": 1, "target": "car", "lost_after_s": 1.0, "min_visibility": 0.1,
}
OFFLINE_DEFAULTS = {"kind": "offline", "name": "", "sequences": None, "trackers": ["gt"], "convention": "otb"}
GENERATION_DEFAULTS = {"maps": ["tracking/easy_urban"], "speeds": [6.0], "frames": 0, "laps": 0, "preset": "",
                       "conditions": ""}
LIST_KEYS = ("maps", "speeds", "trackers", "modes", "fps", "delays_ms", "conditions")
MODES = ("lockstep", "realtime")
FPS = (15.0, 30.0, 60.0)


class ExperimentError(Exception):
    """A bad experiment file; the message names the key or value."""


def _as_list(value):
    return list(value) if isinstance(value, (list, tuple)) else [value]


def _numbers(key, values, lo, hi):
    try:
        out = [float(v) for v in values]
    except (TypeError, ValueError):
        raise ExperimentError("%s: expected numbers, got %r" % (key, values))
    bad = [v for v in out if not lo <= v <= hi]
    if bad:
        raise ExperimentError("%s: %s outside [%g, %g]" % (key, ", ".join("%g" % v for v in bad), lo, hi))
    return out


def check_tracker_spec(spec):
    """ExperimentError naming `spec` unless sim4cv.trackers would accept it
    (without starting it: no process, no import of a python: module)."""
    from . import trackers
    try:
        return trackers.check_tracker_spec(spec)
    except ValueError as e:
        raise ExperimentError("trackers: %s" % e) from None


def _check_map(m, key="maps"):
    if not isinstance(m, str) or not os.path.isfile(os.path.join(REPO_ROOT, "scenes", m + ".map")):
        raise ExperimentError("%s: no map %r (scenes/%s.map)" % (key, m, m))
    return m


def load(path):
    """The experiment in `path`, defaults filled in and every value checked."""
    import yaml
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise ExperimentError("%s: %s" % (path, e))
    if not isinstance(data, dict):
        raise ExperimentError("%s: expected a mapping of keys (kind: online|offline, ...)" % path)
    kind = data.get("kind", "online")
    if kind not in ("online", "offline"):
        raise ExperimentError("kind: %r is neither online nor offline" % (kind,))
    defaults = ONLINE_DEFAULTS if kind == "online" else OFFLINE_DEFAULTS
    unknown = sorted(set(data) - set(defaults))
    if unknown:
        raise ExperimentError("unknown key(s) %s for a %s experiment (known: %s)"
                              % (", ".join(unknown), kind, ", ".join(sorted(defaults))))
    exp = dict(defaults, **data)
    exp["name"] = str(exp["name"] or os.path.splitext(os.path.basename(path))[0])
    exp["trackers"] = [check_tracker_spec(t) for t in _as_list(exp["trackers"])]
    if not exp["trackers"]:
        raise ExperimentError("trackers: empty")
    if len({sanitise(t) for t in exp["trackers"]}) != len(exp["trackers"]):
        raise ExperimentError("trackers: two specifications with the same folder name: %s"
                              % [sanitise(t) for t in exp["trackers"]])
    if kind == "offline":
        return _check_offline(exp)
    for key in LIST_KEYS:
        exp[key] = _as_list(exp[key])
        if not exp[key]:
            raise ExperimentError("%s: empty" % key)
    exp["maps"] = [_check_map(m) for m in exp["maps"]]
    exp["speeds"] = _numbers("speeds", exp["speeds"], 0.1, 40)
    exp["fps"] = _numbers("fps", exp["fps"], 1, 1000)
    if any(f not in FPS for f in exp["fps"]):
        raise ExperimentError("fps: each must be one of 15, 30, 60, got %s" % exp["fps"])
    exp["delays_ms"] = _numbers("delays_ms", exp["delays_ms"], 0, 60000)
    if any(d > 0 for d in exp["delays_ms"]) and "realtime" not in exp["modes"]:
        raise ExperimentError("delays_ms: %s needs modes: [realtime]; in lockstep the simulation waits for every "
                              "answer, so a delay changes nothing it measures" % exp["delays_ms"])
    bad = [m for m in exp["modes"] if m not in MODES]
    if bad:
        raise ExperimentError("modes: unknown %s (choose from lockstep, realtime)" % bad)
    from .sequences import CONDITIONS
    exp["conditions"] = ["" if c in (None, "") else str(c) for c in exp["conditions"]]
    bad = [c for c in exp["conditions"] if c and c not in CONDITIONS]
    if bad:
        raise ExperimentError("conditions: unknown %s (choose from %s, or \"\")" % (bad, ", ".join(CONDITIONS)))
    for key, lo, hi in (("repetitions", 1, 1000), ("uavs_per_run", 1, 16)):
        if not isinstance(exp[key], int) or not lo <= exp[key] <= hi:
            raise ExperimentError("%s: expected an integer in [%d, %d], got %r" % (key, lo, hi, exp[key]))
    if exp["target"] not in ("car", "pedestrian"):
        raise ExperimentError("target: %r (car or pedestrian)" % (exp["target"],))
    for key, lo, hi in (("seconds", 0.1, 36000), ("lost_after_s", 0.0, 3600), ("min_visibility", 0.0, 1.0)):
        exp[key] = _numbers(key, [exp[key]], lo, hi)[0]
    return exp


def _check_offline(exp):
    from .ope import CONVENTIONS
    if exp["convention"] not in CONVENTIONS:
        raise ExperimentError("convention: %r (choose from %s)" % (exp["convention"], ", ".join(CONVENTIONS)))
    seqs = exp["sequences"]
    if isinstance(seqs, str):
        if not os.path.isdir(seqs):
            raise ExperimentError("sequences: no folder %s" % os.path.abspath(seqs))
        return exp
    if not isinstance(seqs, dict):
        raise ExperimentError("sequences: give a folder of sequences or a generation spec (maps, speeds, frames)")
    unknown = sorted(set(seqs) - set(GENERATION_DEFAULTS))
    if unknown:
        raise ExperimentError("unknown key(s) sequences.%s (known: %s)"
                              % (", sequences.".join(unknown), ", ".join(sorted(GENERATION_DEFAULTS))))
    gen = dict(GENERATION_DEFAULTS, **seqs)
    if gen["preset"] not in ("", None, "paper"):
        raise ExperimentError("sequences.preset: %r (only paper)" % gen["preset"])
    gen["maps"] = [_check_map(m, "sequences.maps") for m in _as_list(gen["maps"])]
    gen["speeds"] = _numbers("sequences.speeds", _as_list(gen["speeds"]), 0.1, 40)
    for key in ("frames", "laps"):
        if not isinstance(gen[key], int) or gen[key] < 0:
            raise ExperimentError("sequences.%s: expected an integer >= 0, got %r" % (key, gen[key]))
    if not gen["preset"] and gen["frames"] and gen["laps"]:
        raise ExperimentError("sequences: give frames or laps, not both")
    exp["sequences"] = gen
    return exp


def sanitise(text):
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", str(text)).strip("_")


def online_runs(exp):
    """Every run of an online experiment: dicts with its name, Session
    keyword arguments and the labels of its records."""
    n = exp["uavs_per_run"]
    groups = [exp["trackers"][i:i + n] for i in range(0, len(exp["trackers"]), n)]
    runs = []
    for m in exp["maps"]:
        for speed in exp["speeds"]:
            for mode in exp["modes"]:
                for fps in exp["fps"]:
                    for delay in exp["delays_ms"]:
                        if mode == "lockstep" and delay > 0:
                            continue  # run_session refuses it: the lockstep control runs at delay 0
                        for cond in exp["conditions"]:
                            for rep in range(1, exp["repetitions"] + 1):
                                for group in groups:
                                    name = "%s_s%g_%s_fps%g_d%g%s_r%d__%s" % (
                                        sanitise(m.split("/")[-1] if m.startswith("tracking/") else m), speed,
                                        mode, fps, delay, "_" + cond if cond else "", rep,
                                        "+".join(sanitise(t) for t in group))
                                    runs.append({"name": name, "repetition": rep, "session": dict(
                                        map=m, speed=speed, trackers=group, mode=mode, fps=fps, delay_ms=delay,
                                        conditions=cond, seconds=exp["seconds"], target=exp["target"],
                                        lost_after_s=exp["lost_after_s"], min_visibility=exp["min_visibility"])})
    return runs


def _read_session(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def _run_online(run, out_dir, address):
    from .tracking import Session, run_session
    run_dir = os.path.join(out_dir, "runs", run["name"])
    done = _read_session(os.path.join(run_dir, "session.json"))
    if done is not None:
        return run, done, True
    shutil.rmtree(run_dir, ignore_errors=True)  # an interrupted run is redone from scratch
    t0 = time.monotonic()
    try:
        summary = run_session(Session(**run["session"]), run_dir, address)
    except Exception as e:  # e.g. the daemon did not start: recorded, not saved (a resume retries it)
        error = "run failed: %s: %s" % (type(e).__name__, e)
        return run, {"results": [{"tracker": t, "lost": True, "error": error} for t in run["session"]["trackers"]],
                     "wall_s": time.monotonic() - t0}, False
    summary["wall_s"] = time.monotonic() - t0
    with open(os.path.join(run_dir, "session.json.part"), "w") as f:
        from .strict_json import dump
        dump(summary, f, indent=1)
    os.replace(os.path.join(run_dir, "session.json.part"), os.path.join(run_dir, "session.json"))  # whole or absent
    return run, summary, False


RECORD_KEYS = ["kind", "run", "map", "speed", "tracker", "mode", "fps", "delay_ms", "conditions", "repetition",
               "uav", "completion", "frames_processed", "frames_skipped", "tracker_fps", "mean_center_error_px",
               "median_center_error_px", "mean_distance_m", "seconds", "lost", "error", "wall_s"]


def online_records(run, summary):
    s = run["session"]
    out = []
    for k, r in enumerate(summary["results"]):
        rec = {"kind": "online", "run": run["name"], "map": s["map"], "speed": s["speed"],
               "tracker": r.get("tracker", s["trackers"][k]), "mode": s["mode"], "fps": s["fps"],
               "delay_ms": s["delay_ms"], "conditions": s["conditions"], "repetition": run["repetition"],
               "uav": k, "wall_s": summary.get("wall_s", math.nan)}
        for key in RECORD_KEYS[11:-1]:
            rec[key] = r.get(key, "" if key == "error" else math.nan)
        rec["lost"] = bool(r.get("lost", True))
        rec["completion"] = r.get("completion", 0.0 if r.get("error") else math.nan)
        out.append(rec)
    return out


class Progress:
    """done/total, elapsed and estimated remaining time on stderr."""

    def __init__(self, total, jobs, label):
        self.total, self.jobs, self.label = total, jobs, label
        self.done, self.ran, self.ran_s, self.t0 = 0, 0, 0.0, time.monotonic()
        self.say("%d %s to do, %d at a time" % (total, label, jobs))

    def say(self, text):
        print("sim4cv.experiment: %s" % text, file=sys.stderr, flush=True)

    def step(self, name, skipped, seconds, note=""):
        self.done += 1
        if not skipped:
            self.ran, self.ran_s = self.ran + 1, self.ran_s + seconds
        elapsed = time.monotonic() - self.t0
        left = self.total - self.done
        eta = "~%.0f s left" % (self.ran_s / self.ran * left / self.jobs) if self.ran and left else \
            ("done" if not left else "? left")
        self.say("[%d/%d] %s %s%s; elapsed %.0f s, %s" % (self.done, self.total, name,
                                                           "skipped (done before)" if skipped else
                                                           "in %.1f s" % seconds, note, elapsed, eta))


def _uav_track(out_dir, record):
    """(sim times, x, y) of a record's UAV from its run's frames CSV."""
    path = os.path.join(out_dir, "runs", record["run"], "frames_%d.csv" % record["uav"])
    times, xs, ys = [], [], []
    if os.path.exists(path):
        with open(path) as f:
            for row in csv.DictReader(f):
                times.append(float(row["sim_time"]))
                xs.append(float(row["uav_x"]))
                ys.append(float(row["uav_y"]))
    return times, xs, ys


def add_gt_deviation(records, out_dir):
    """deviation_from_gt_m: the mean distance between a UAV and the
    ground-truth tracker's UAV at the same sim time (the gt run of the same
    map, speed, mode, fps, conditions and repetition; one with the same
    delay if there is one), over the frames the tracker flew; NaN without a
    gt run."""
    setting = ("map", "speed", "mode", "fps", "conditions", "repetition")
    references = {}
    for r in records:
        if r["tracker"] == "gt":
            key = tuple(r[k] for k in setting)
            if key not in references or r["delay_ms"] == 0:
                references[key] = r
    tracks = {}
    for r in records:
        ref = references.get(tuple(r[k] for k in setting))
        r["deviation_from_gt_m"] = math.nan
        if ref is None:
            continue
        for rec in (r, ref):
            if id(rec) not in tracks:
                tracks[id(rec)] = _uav_track(out_dir, rec)
        gt_t, gt_x, gt_y = tracks[id(ref)]
        t, x, y = tracks[id(r)]
        distances = []
        for ti, xi, yi in zip(t, x, y):
            j = min(bisect.bisect_left(gt_t, ti), len(gt_t) - 1) if gt_t else -1
            if j >= 0 and abs(gt_t[j] - ti) < 0.1:
                distances.append(math.hypot(xi - gt_x[j], yi - gt_y[j]))
        if distances:
            r["deviation_from_gt_m"] = sum(distances) / len(distances)



if __name__ == "__main__":
    multiprocessing.freeze_support()
    from sim4cv.experiment_cli import main  # the command line lives there; this file is only its -m name
    sys.exit(main())
