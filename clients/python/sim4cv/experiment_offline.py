"""The offline part of sim4cv.experiment: sequences (a folder, or generated
into OUT/sequences by sim4cv.sequences), every tracker over every sequence's
img/*.jpg (initialised on the first frame's ground truth), results in the
groundtruth_rect format, then sim4cv.ope.

    OUT/results/<tracker>/<seq>.txt        x,y,w,h per frame (line 1: the initial box); NaN,NaN,NaN,NaN: no box
    OUT/results/<tracker>/<seq>_time.txt   seconds per frame of the tracker (got10k's format; line 1: init)
    OUT/ope/ope.json + PNGs                sim4cv.ope's report and plots

`gt` offline answers each frame with the sequence's ground-truth line (the
reference: AUC and precision at their best). A result file is written last,
by renaming, so one that exists is complete and is skipped on resume.
"""

import glob
import math
import os
import time

import numpy as np


def generation_specs(exp):
    """The sim4cv.sequences Specs to generate into OUT/sequences ([] when the
    experiment names a folder of sequences)."""
    seqs = exp["sequences"]
    if isinstance(seqs, str):
        return []
    from . import sequences as sq
    cond = seqs["conditions"] or None
    if seqs["preset"] == "paper":
        return sq.paper_specs(cond)
    frames, laps = (seqs["frames"], 0) if seqs["frames"] else (0, seqs["laps"] or 1)
    return [sq.Spec(m, s, frames=frames, laps=laps, conditions=cond) for m in seqs["maps"] for s in seqs["speeds"]]


def sequences_root(exp, out_dir):
    return exp["sequences"] if isinstance(exp["sequences"], str) else os.path.join(out_dir, "sequences")


# Run in every offline study beside the trackers asked for: the ceiling (gt) and
# what doing nothing scores (the baselines), so every table shows the range.
REFERENCE_TRACKERS = ("gt", "baseline:static", "baseline:centre")


def with_references(trackers):
    return list(trackers) + [t for t in REFERENCE_TRACKERS if t not in trackers]


def list_sequences(root):
    return sorted(d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "groundtruth_rect.txt")))


def _fmt(box):
    if box is None or any(not math.isfinite(v) for v in box):
        return "NaN,NaN,NaN,NaN"
    return ",".join("%.2f" % v for v in box)


def track_sequence(spec, seq_dir, result_path):
    """Runs `spec` over one sequence; writes the result and time files.
    Returns (frames, tracker seconds, error text)."""
    import cv2
    from .ope import read_boxes
    from .trackers import make_tracker
    truth = read_boxes(os.path.join(seq_dir, "groundtruth_rect.txt"))
    images = sorted(glob.glob(os.path.join(seq_dir, "img", "*.jpg")))
    if not images:
        return 0, 0.0, "no img/*.jpg in %s" % seq_dir
    if len(truth) == 0 or not np.all(np.isfinite(truth[0])):
        return 0, 0.0, "%s: the first frame has no ground-truth box to start from" % seq_dir
    boxes, times = [tuple(truth[0])], [0.0]
    tracker = None if spec == "gt" else make_tracker(spec)
    try:
        for i, path in enumerate(images):
            rgb = cv2.cvtColor(cv2.imread(path, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
            t0 = time.perf_counter()
            if i == 0:
                if tracker is not None:
                    tracker.init(rgb, tuple(float(v) for v in truth[0]))
            elif tracker is None:
                boxes.append(tuple(truth[i]) if i < len(truth) else None)
            else:
                boxes.append(tracker.update(rgb))
            if i == 0:
                times[0] = time.perf_counter() - t0
            else:
                times.append(time.perf_counter() - t0)
    finally:
        if tracker is not None:
            tracker.close()
    os.makedirs(os.path.dirname(result_path), exist_ok=True)
    with open(result_path[:-4] + "_time.txt", "w") as f:
        f.write("".join("%.6f\n" % t for t in times))
    with open(result_path + ".part", "w") as f:
        f.write("".join(_fmt(b) + "\n" for b in boxes))
    os.replace(result_path + ".part", result_path)
    return len(images), sum(times[1:]), ""


def _fps_per_frame(base):
    """got10k's speed: the mean of 1/t over the lines of <seq>_time.txt with t > 0 (the init line included)."""
    from .sequence_export import per_frame_fps
    try:
        with open(base + "_time.txt") as f:
            return per_frame_fps([float(line) for line in f if line.strip()])
    except (OSError, ValueError):
        return math.nan


def score_one(args):
    """One (tracker, sequence) of score_work: (..., frames, seconds, error, skipped, wall)."""
    spec, tracker_name, seq, seq_dir, result_path = args
    t0 = time.monotonic()
    if os.path.exists(result_path):
        frames, seconds = _read_times(result_path)
        return spec, tracker_name, seq, frames, seconds, "", True, 0.0
    try:
        frames, seconds, error = track_sequence(spec, seq_dir, result_path)
    except Exception as e:  # one tracker's failure on one sequence is a record, not the end of the study
        frames, seconds, error = 0, 0.0, "%s: %s" % (type(e).__name__, e)
    return spec, tracker_name, seq, frames, seconds, error, False, time.monotonic() - t0


def _read_times(result_path):
    try:
        with open(result_path[:-4] + "_time.txt") as f:
            times = [float(line) for line in f if line.strip()]
        return len(times), sum(times[1:])
    except (OSError, ValueError):
        return 0, math.nan


def score_work(exp, root, out_dir, seqs):
    """(tracker, folder name, sequence, sequence folder, result file) for every tracker x sequence."""
    from .experiment import sanitise
    results_dir = os.path.join(out_dir, "results")
    return [(spec, sanitise(spec), seq, os.path.join(root, seq), os.path.join(results_dir, sanitise(spec), seq + ".txt"))
            for spec in with_references(exp["trackers"]) for seq in seqs]


def score_record(work, frames, seconds, error):
    """The record of one score_work item: (tracker, folder name, sequence, sequence folder, result file)."""
    spec, name, seq, _, result_path = work
    return {"kind": "offline", "tracker": spec, "tracker_dir": name, "sequence": seq, "frames": frames,
            "tracker_fps": (frames - 1) / seconds if seconds and frames > 1 else math.nan,
            "fps_per_frame": _fps_per_frame(result_path[:-len(".txt")]), "error": error}


def write_ope(exp, out_dir, root, say):
    """Scores whatever results there are (sim4cv.ope) into OUT/ope; the report."""
    from . import ope
    from .experiment import sanitise
    results_dir = os.path.join(out_dir, "results")
    ope_dir = os.path.join(out_dir, "ope")
    os.makedirs(ope_dir, exist_ok=True)
    names = [sanitise(t) for t in with_references(exp["trackers"]) if os.path.isdir(os.path.join(results_dir, sanitise(t)))]
    report = ope.evaluate(root, results_dir, exp["convention"], trackers=names)
    try:
        from . import ope_plots
        report["plots"] = [os.path.basename(p) for p in ope_plots.plot_report(report, ope_dir)]
    except ImportError as e:
        report["plots"] = []
        report["warnings"].append("plots skipped: %s" % e)
    import json
    with open(os.path.join(ope_dir, "ope.json"), "w") as f:
        json.dump(report, f, indent=1, allow_nan=False)
    for w in report["warnings"]:
        say("ope warning: %s" % w)
    return report
