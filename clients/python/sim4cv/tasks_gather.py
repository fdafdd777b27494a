"""results.json, results.csv, plots and report.md of a task folder
(sim4cv.tasks) from whatever tasks are done; a failed or missing task is a
record with its error, and report.md lists them (docs/scaling.md)."""

import os
import sys
import time

from . import experiment as ex
from . import experiment_offline as off
from . import tasks as tk

# The error of the record that stands for a task not run yet (a study gathered part way).
NOT_RUN = "missing: "


def _not_run(index):
    return NOT_RUN + "task %d has not run" % index


def _online_records(out_dir, st):
    records = []
    for t in st["tasks"]:
        run = t["run"]
        summary = ex._read_session(os.path.join(out_dir, "runs", t["name"], "session.json"))
        if summary is None:
            error = st["failed"].get(t["index"], _not_run(t["index"]))
            summary = {"results": [{"tracker": s, "lost": True, "error": error} for s in run["session"]["trackers"]]}
        records += ex.online_records(run, summary)
    ex.add_gt_deviation(records, out_dir)
    return records


def _offline_records(exp, out_dir, st, say):
    records = []
    for t in st["tasks"]:
        if t["kind"] != "score":
            continue
        if t["index"] in st["done"]:
            *_, frames, seconds, error, _, _ = off.score_one(tuple(t["work"]))
        else:
            frames, seconds = 0, 0.0
            error = st["failed"].get(t["index"], _not_run(t["index"]))
        records.append(off.score_record(tuple(t["work"]), frames, seconds, error))
    root = off.sequences_root(exp, out_dir)
    try:
        report = off.write_ope(exp, out_dir, root, say)
    except Exception as e:  # nothing scored yet: the tables still say what is missing
        say("ope skipped: %s: %s" % (type(e).__name__, e))
        report = None
    return records, report


def _command_report(out_dir, st, command):
    """A plan of commands has no tables of its own: report.md lists each
    command's state (its outputs are wherever the command wrote them)."""
    lines = ["# Commands (%d: %d done, %d failed, %d missing)" % (len(st["tasks"]), len(st["done"]),
                                                                   len(st["failed"]), len(st["missing"])),
             "", "- command: `%s`" % command, ""]
    for t in st["tasks"]:
        i = t["index"]
        state = "done" if i in st["done"] else ("failed: " + st["failed"][i]) if i in st["failed"] else "missing"
        lines.append("- %d `%s`: %s" % (i, t["name"], state))
    with open(os.path.join(out_dir, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    return [], ["report.md"], st


def gather(out_dir, command, wall_s=None):
    """Writes the study's outputs from what is done; returns (records, written files, status)."""
    from . import experiment_report as report
    say = lambda text: print("sim4cv.experiment: %s" % text, file=sys.stderr, flush=True)  # noqa: E731
    t0 = time.monotonic()
    out_dir = os.path.abspath(out_dir)
    exp, _ = tk.load_plan(out_dir)
    st = tk.status(out_dir)
    if exp["kind"] == "commands":
        return _command_report(out_dir, st, command)
    if exp["kind"] == "online":
        records, ope_report = _online_records(out_dir, st), None
    else:
        records, ope_report = _offline_records(exp, out_dir, st, say)
    written = report.write_all(exp, records, out_dir, command, time.monotonic() - t0 if wall_s is None else wall_s,
                               ope_report)
    if st["failed"] or st["missing"]:
        lines = ["", "## Tasks not done (%d of %d; `python3 -m sim4cv.experiment status %s`)" % (
            len(st["failed"]) + len(st["missing"]), len(st["tasks"]), out_dir), ""]
        lines += ["- %d %s: failed: %s" % (i, st["tasks"][i]["name"], why) for i, why in sorted(st["failed"].items())]
        lines += ["- %d %s: missing" % (i, st["tasks"][i]["name"]) for i in st["missing"]]
        with open(os.path.join(out_dir, "report.md"), "a") as f:
            f.write("\n".join(lines) + "\n")
    return records, written, st
