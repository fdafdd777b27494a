"""PNG success and precision plots of an OPE report (sim4cv.ope.evaluate), as
the OTB/UAV123 toolkits draw them: one curve per tracker, the legend sorted by
score (success: AUC, precision: precision at 20 px), "name [0.xxx]" (plus
"(k of n sequences)" for a tracker whose results lack some).

Files: success_overall.png, precision_overall.png and, per attribute with at
least one sequence, success_<ABBREV>.png, precision_<ABBREV>.png (characters
other than letters, digits, '-' and '_' in ABBREV become '_').
Importing this module imports matplotlib (Agg backend).
"""

import os
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

_STYLES = ["-", "--", "-.", ":"]


def _safe(name):
    return re.sub(r"[^A-Za-z0-9_-]", "_", name)


def ranked(entries, kind):
    """entries [(tracker, scores dict)] best first: by success_auc ("success")
    or precision_20 ("precision"), ties by name."""
    key = "success_auc" if kind == "success" else "precision_20"
    return sorted(entries, key=lambda e: (-e[1][key], e[0]))


def draw(path, title, thresholds, entries, kind, total=None):
    """One plot. entries: [(tracker, scores dict)]; kind: "success" or
    "precision"; total: the sequence count, noted for trackers with fewer."""
    key, curve = ("success_auc", "success_curve") if kind == "success" else ("precision_20", "precision_curve")
    ranked_entries = ranked(entries, kind)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    try:
        for i, (name, scores) in enumerate(ranked_entries):
            label = "%s [%.3f]" % (name, scores[key])
            if total is not None and scores["sequences"] < total:
                label += " (%d of %d sequences)" % (scores["sequences"], total)
            ax.plot(thresholds, scores[curve], _STYLES[(i // 10) % len(_STYLES)], linewidth=2, label=label)
        if kind == "success":
            ax.set(xlabel="Overlap threshold", ylabel="Success rate", xlim=(0, 1), ylim=(0, 1))
            loc = "lower left"
        else:
            ax.set(xlabel="Location error threshold", ylabel="Precision", xlim=(0, thresholds[-1]), ylim=(0, 1))
            loc = "lower right"
        ax.set_title(title)
        ax.grid(True)
        if ranked_entries:
            ax.legend(loc=loc, fontsize=8)
        fig.tight_layout()
        fig.savefig(path, dpi=100)
    finally:
        plt.close(fig)
    return path


def plot_report(report, out_dir):
    """Writes the PNGs of `report` into out_dir; returns their paths."""
    trackers = report["trackers"]
    ious, dists = report["success_thresholds"], report["precision_thresholds"]
    written = []
    overall = [(name, t) for name, t in trackers.items() if t["sequences"] > 0]
    for kind, thresholds in (("success", ious), ("precision", dists)):
        title = "%s plots of OPE" % kind.capitalize()
        written.append(draw(os.path.join(out_dir, "%s_overall.png" % kind), title, thresholds, overall, kind,
                            len(report["sequences"])))
    for abbrev, attribute in report.get("attributes", {}).items():
        entries = [(name, t["per_attribute"][abbrev]) for name, t in trackers.items() if abbrev in t["per_attribute"]]
        if not entries:
            continue
        count = len(attribute["sequences"])
        for kind, thresholds in (("success", ious), ("precision", dists)):
            title = "%s plots of OPE - %s (%d)" % (kind.capitalize(), attribute["name"], count)
            path = os.path.join(out_dir, "%s_%s.png" % (kind, _safe(abbrev)))
            written.append(draw(path, title, thresholds, entries, kind, count))
    return written
