"""Tables, plots and report.md of sim4cv.experiment (docs/tracking.md,
"Experiments"). Plots use matplotlib's Agg backend; trajectory maps are
sim4cv_logdraw (every UAV of every run log, one colour per log): $SIM4CV_LOGDRAW, else the
source tree's build/tools/, else an installed one."""

import csv
import math
import os
import platform
import statistics
import subprocess

from . import strict_json
from .daemon import IN_SOURCE_TREE, REPO_ROOT, installed_program

LOGDRAW = os.environ.get("SIM4CV_LOGDRAW") or (
    os.path.join(REPO_ROOT, "build", "tools", "sim4cv_logdraw") if IN_SOURCE_TREE
    else installed_program("sim4cv_logdraw") or "sim4cv_logdraw")


def machine():
    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return "%s, %d cores (nproc)" % (model, len(os.sched_getaffinity(0)))


def _f(v, fmt="%.3f"):
    if v is None:  # a missing number read back from strict JSON
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "-" if math.isnan(v) else fmt % v
    return str(v)


def _mean(values):
    values = [v for v in values if isinstance(v, (int, float)) and not math.isnan(v)]
    return statistics.fmean(values) if values else math.nan


def write_tables(records, out_dir):
    keys = []
    for r in records:
        keys += [k for k in r if k not in keys]
    with open(os.path.join(out_dir, "results.json"), "w") as f:
        strict_json.dump(records, f, indent=1)  # null, not NaN: every JSON parser reads it
    with open(os.path.join(out_dir, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(records)
    return ["results.json", "results.csv"]


def _settings(records):
    return sorted({(r["mode"], r["fps"], r["conditions"]) for r in records})


def _setting_text(s):
    return "%s, %g fps%s" % (s[0], s[1], ", " + s[2] if s[2] else "")


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def completion_plots(records, trackers, plots_dir):
    """One grouped bar chart per setting (mode, fps, conditions): groups
    (map, speed, delay), a bar per tracker, the mean over repetitions with min-max bars."""
    plt = _plt()
    written = []
    settings = _settings(records)
    for s in settings:
        recs = [r for r in records if (r["mode"], r["fps"], r["conditions"]) == s]
        groups = sorted({(r["map"], r["speed"], r["delay_ms"]) for r in recs})
        delays = len({g[2] for g in groups}) > 1
        fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(groups) * max(1, len(trackers)) ** 0.5 + 3), 4.2))
        width = 0.8 / len(trackers)
        for k, t in enumerate(trackers):
            means, lo, hi = [], [], []
            for g in groups:
                vals = [r["completion"] for r in recs if (r["map"], r["speed"], r["delay_ms"]) == g
                        and r["tracker"] == t and isinstance(r["completion"], (int, float))
                        and not math.isnan(r["completion"])]
                m = statistics.fmean(vals) if vals else 0.0
                means.append(m)
                # at least 0: the mean of equal values can round a bit past them (fmean([0.094] * 3) > 0.094)
                lo.append(max(m - min(vals), 0.0) if vals else 0.0)
                hi.append(max(max(vals) - m, 0.0) if vals else 0.0)
            xs = [i + (k - (len(trackers) - 1) / 2) * width for i in range(len(groups))]
            ax.bar(xs, means, width, yerr=[lo, hi], capsize=3, label=t)
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels(["%s\n%g m/s%s" % (m.split("/")[-1], v, "\n+%g ms" % d if delays else "")
                            for m, v, d in groups])
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("completion (mean; bars: min-max over repetitions)")
        ax.set_title("Completion, " + _setting_text(s))
        ax.legend(fontsize=8, loc="lower left")
        fig.tight_layout()
        name = "completion.png" if len(settings) == 1 else "completion_%s_fps%g%s.png" % (
            s[0], s[1], "_" + s[2] if s[2] else "")
        fig.savefig(os.path.join(plots_dir, name), dpi=110)
        plt.close(fig)
        written.append(name)
    return written


def latency_plot(records, trackers, plots_dir):
    """Completion and mean centre error vs delay_ms, a line per tracker (and map/speed/mode)."""
    records = [r for r in records if r["mode"] == "realtime"]  # a delay means nothing in lockstep
    if len({r["delay_ms"] for r in records}) < 2:
        return []
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    lines = sorted({(r["tracker"], r["map"], r["speed"], r["mode"], r["fps"]) for r in records},
                   key=lambda x: (trackers.index(x[0]),) + x[1:])
    several = len({x[1:] for x in lines}) > 1
    for line in lines:
        recs = [r for r in records if (r["tracker"], r["map"], r["speed"], r["mode"], r["fps"]) == line]
        delays = sorted({r["delay_ms"] for r in recs})
        label = line[0] + (" %s %g m/s %s" % (line[1].split("/")[-1], line[2], line[3]) if several else "")
        for ax, key in zip(axes, ("completion", "mean_center_error_px")):
            vals = [[r[key] for r in recs if r["delay_ms"] == d] for d in delays]
            means = [_mean(v) for v in vals]
            ax.errorbar(delays, means, marker="o", capsize=3, label=label,
                        yerr=[[m - min(v) if not math.isnan(m) else 0 for m, v in zip(means, vals)],
                              [max(v) - m if not math.isnan(m) else 0 for m, v in zip(means, vals)]])
    axes[0].set_ylim(0, 1.05)
    axes[0].set_ylabel("completion")
    axes[1].set_ylabel("mean centre error (px)")
    for ax in axes:
        ax.set_xlabel("added tracker delay (ms)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(plots_dir, "latency.png"), dpi=110)
    plt.close(fig)
    return ["latency.png"]


def trajectory_maps(records, out_dir, plots_dir):
    """sim4cv_logdraw per (map, speed) over its runs' logs, linked under
    plots/logs/<run>.s4log so that the legend names the run."""
    written = []
    if not os.access(LOGDRAW, os.X_OK):
        return written, ["trajectory maps skipped: no %s (build the tools)" % LOGDRAW]
    notes = []
    links = os.path.join(plots_dir, "logs")
    os.makedirs(links, exist_ok=True)
    for m, speed in sorted({(r["map"], r["speed"]) for r in records}):
        logs = []
        for run in sorted({r["run"] for r in records if (r["map"], r["speed"]) == (m, speed)}):
            src = os.path.join(out_dir, "runs", run, "run.s4log")
            if os.path.exists(src):
                link = os.path.join(links, run + ".s4log")
                if os.path.lexists(link):
                    os.remove(link)
                os.symlink(os.path.relpath(src, links), link)
                logs.append(link)
        if not logs:
            continue
        name = "trajectories_%s_s%g.png" % (m.replace("/", "_"), speed)
        cmd = [LOGDRAW, "--map", os.path.join(REPO_ROOT, "scenes", m + ".map"),
               "--out", os.path.join(plots_dir, name)] + logs
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode == 0:
            written.append(name)
        else:
            notes.append("sim4cv_logdraw failed for %s at %g m/s: %s" % (m, speed, proc.stderr.strip()[-300:]))
    return written, notes


ONLINE_COLUMNS = ["map", "speed", "tracker", "mode", "fps", "delay_ms", "runs", "completion", "completion_sd",
                  "completion_range", "lost",
                  "frames_processed", "frames_skipped", "tracker_fps", "mean_center_error_px", "deviation_from_gt_m"]


def summary_rows(records):
    """One row per (map, speed, tracker, mode, fps, delay, conditions): means over repetitions."""
    keys = []
    for r in records:
        k = (r["map"], r["speed"], r["tracker"], r["mode"], r["fps"], r["delay_ms"], r["conditions"])
        if k not in keys:
            keys.append(k)
    rows = []
    for k in keys:
        recs = [r for r in records if (r["map"], r["speed"], r["tracker"], r["mode"], r["fps"], r["delay_ms"],
                                       r["conditions"]) == k]
        row = dict(zip(["map", "speed", "tracker", "mode", "fps", "delay_ms", "conditions"], k))
        row["runs"] = len(recs)
        row["lost"] = "%d/%d" % (sum(bool(r["lost"]) for r in recs), len(recs))
        for key in ("completion", "frames_processed", "frames_skipped", "tracker_fps", "mean_center_error_px",
                    "deviation_from_gt_m"):
            row[key] = _mean([r.get(key, math.nan) for r in recs])
        # the spread over repetitions: real time is not deterministic, one run is one sample
        done = [r["completion"] for r in recs if isinstance(r.get("completion"), (int, float))
                and not math.isnan(r["completion"])]
        row["completion_sd"] = statistics.stdev(done) if len(done) > 1 else math.nan
        row["completion_range"] = "%.3f-%.3f" % (min(done), max(done)) if done else "-"
        row["errors"] = "; ".join(sorted({r["error"] for r in recs if r["error"]}))
        rows.append(row)
    return rows


def _md_table(columns, rows, formats=None):
    formats = formats or {}
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        out.append("| " + " | ".join(_f(r[c], formats.get(c, "%.3f")) for c in columns) + " |")
    return out


FORMATS = {"deviation_from_gt_m": "%.1f", "frames_processed": "%.0f", "frames_skipped": "%.0f", "tracker_fps": "%.0f", "mean_center_error_px": "%.1f",
           "speed": "%g", "fps": "%g", "delay_ms": "%g"}


# the offline table's scores (sim4cv.ope): success AUC, P@20, SR0.5, SR0.75, AO, normalised precision at 0.2
OPE_SCORES = ("success_auc", "precision_20", "sr_50", "sr_75", "ao", "norm_precision_20")


def write_all(exp, records, out_dir, command, wall_s, ope_report=None):
    written = write_tables(records, out_dir)
    plots_dir = os.path.join(out_dir, "plots")
    os.makedirs(plots_dir, exist_ok=True)
    lines = ["# Experiment %s (%s)" % (exp["name"], exp["kind"]), "",
             "- command: `%s`" % command, "- machine: %s" % machine(),
             "- wall time of this invocation: %.1f s (runs done before and skipped cost nothing here)" % wall_s,
             "- records: %d (results.json, results.csv)" % len(records), ""]
    notes = []
    if exp["kind"] == "online":
        run_wall = _mean([r["wall_s"] for r in records if r["uav"] == 0]) if records else math.nan
        total = sum(r["wall_s"] for r in records if r["uav"] == 0 and not math.isnan(r["wall_s"]))
        lines[4:4] = ["- runs: %d, %.0f s of sim time each; wall time per run %.1f s on average, %.0f s summed "
                      "(when they ran)" % (len({r["run"] for r in records}), exp["seconds"], run_wall, total)]
        plots = completion_plots(records, exp["trackers"], plots_dir) + latency_plot(records, exp["trackers"],
                                                                                      plots_dir)
        maps, notes = trajectory_maps(records, out_dir, plots_dir)
        rows = summary_rows(records)
        lines += ["## Results (means over repetitions)", ""] + _md_table(ONLINE_COLUMNS, rows, FORMATS)
        errors = [r for r in rows if r["errors"]]
        if errors:
            lines += ["", "Errors:", ""] + ["- %s %s %g m/s: %s" % (r["tracker"], r["map"], r["speed"], r["errors"])
                                            for r in errors]
        lines += ["", "## Plots", ""] + ["![%s](plots/%s)" % (p, p) for p in plots + maps]
        written += ["plots/" + p for p in plots + maps]
    else:
        from .experiment_offline import with_references
        rows = []
        total = len((ope_report or {}).get("sequences", []))
        for spec in with_references(exp["trackers"]):
            recs = [r for r in records if r["tracker"] == spec]
            t = (ope_report or {}).get("trackers", {}).get(recs[0]["tracker_dir"] if recs else "", {})
            rows.append({"tracker": spec, **{k: t.get(k, math.nan) for k in OPE_SCORES},
                         "sequences": t.get("sequences", 0), "frames": sum(r["frames"] for r in recs),
                         "tracker_fps": _mean([r["tracker_fps"] for r in recs]),
                         "fps_per_frame": _mean([r.get("fps_per_frame", math.nan) for r in recs]),
                         "errors": "; ".join(r["sequence"] + ": " + r["error"] for r in recs if r["error"])})
        # a tracker scored on fewer sequences than the others is not ranked with them: it goes below, marked
        for r in rows:
            r["ranked"] = r["sequences"] == total and total > 0
            if not r["ranked"]:
                r["tracker"] += " (%d of %d sequences: not ranked)" % (r["sequences"], total)
        rows.sort(key=lambda r: (not r["ranked"], -r["success_auc"] if not math.isnan(r["success_auc"]) else 1))
        lines += ["## OPE (%s convention; ope/ope.json)" % exp["convention"], ""] + _md_table(
            ["tracker"] + list(OPE_SCORES) + ["sequences", "frames", "tracker_fps", "fps_per_frame"], rows,
            dict(FORMATS, sequences="%d", frames="%d", fps_per_frame="%.0f"))
        lines += ["", "tracker_fps: frames / summed update time; fps_per_frame: the mean of 1/t over the frames "
                  "(got10k's speed). gt and the baselines are references: the ceiling and what doing nothing "
                  "scores."]
        lines += ["", "Per sequence (results/<tracker>/<seq>.txt; fps from <seq>_time.txt):", ""] + _md_table(
            ["tracker", "sequence", "frames", "tracker_fps", "error"], records, FORMATS)
        plots = (ope_report or {}).get("plots", [])
        lines += ["", "## Plots", ""] + ["![%s](ope/%s)" % (p, p) for p in plots]
        notes = (ope_report or {}).get("warnings", [])
    if notes:
        lines += ["", "## Notes", ""] + ["- " + n for n in notes]
    with open(os.path.join(out_dir, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    return written + ["report.md"]
