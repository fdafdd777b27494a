"""An online study's real-time cells beside their lockstep control, one row per
(map, speed, tracker): docs/tracking.md, "The paper's online study".

    /usr/bin/python3 tools/online_control_table.py REALTIME_DIR LOCKSTEP_DIR

Each DIR is an experiment's --out (its results.json, written by `run` or
`gather`). A real-time loss the lockstep control does not have is one of speed
(frames skipped); a loss in both is one of tracking."""
import argparse
import json
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "clients" / "python"))
from sim4cv.experiment_report import summary_rows  # noqa: E402
from sim4cv.tasks_gather import NOT_RUN  # noqa: E402


def cells(out_dir, mode):
    """(map, speed, tracker) -> summary row of the runs of `mode` in OUT_DIR/results.json that
    ran (a study gathered part way has records for its missing tasks too); and how many did not."""
    with open(pathlib.Path(out_dir) / "results.json") as f:
        records = [r for r in json.load(f) if r["mode"] == mode]
    ran = [r for r in records if not r["error"].startswith(NOT_RUN)]
    return {(r["map"], r["speed"], r["tracker"]): r for r in summary_rows(ran)}, len(records) - len(ran)


def number(value, fmt):
    return "-" if not isinstance(value, (int, float)) or math.isnan(value) else fmt % value


def table(realtime, lockstep):
    lines = ["| map | speed | tracker | real time: runs | completion: mean (sd) | range | lost | frames skipped "
             "| tracker fps | lockstep: completion | lost |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for key, rt in realtime.items():
        control = lockstep.get(key)
        lines.append("| %s | %g | %s | %d | %s (%s) | %s | %s | %s | %s | %s | %s |" % (
            key[0].split("/")[-1], key[1], key[2], rt["runs"], number(rt["completion"], "%.3f"),
            number(rt["completion_sd"], "%.3f"), rt["completion_range"], rt["lost"],
            number(rt["frames_skipped"], "%.0f"), number(rt["tracker_fps"], "%.0f"),
            number(control["completion"], "%.3f") if control else "not run", control["lost"] if control else "-"))
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("realtime", help="the real-time study's --out")
    p.add_argument("lockstep", help="its lockstep control's --out")
    args = p.parse_args(argv)
    (realtime, realtime_missing), (lockstep, lockstep_missing) = cells(args.realtime, "realtime"), \
        cells(args.lockstep, "lockstep")
    print(table(realtime, lockstep))
    if realtime_missing or lockstep_missing:
        print("\nNot run yet: %d real-time and %d lockstep runs (resume with the experiment's `run` or `resubmit`)."
              % (realtime_missing, lockstep_missing))
    return 0


if __name__ == "__main__":
    sys.exit(main())
