"""Command line of the OPE evaluation (also `python3 -m sim4cv.ope`):

    python3 -m sim4cv.ope --sequences DIR --results DIR --out DIR
                          [--convention otb|got10k] [--trackers a,b] [--origin 0|1]
                          [--require-all] [--matlab-drop-zero-curves]

Writes OUT/ope.json (sim4cv.ope.evaluate's report, plus "plots": the PNGs
written) and the PNGs of sim4cv.ope_plots. Without matplotlib it still writes
ope.json, with a warning that the plots were skipped. Exit status: 0, or 2
for bad arguments or a malformed / missing input file (the message names it).
"""

import argparse
import json
import os
import sys

from . import ope


def parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.ope",
                                description="One-pass evaluation (success and precision plots) of trackers; "
                                            "docs/tracking.md, 'Offline evaluation (OPE)'.")
    p.add_argument("--sequences", required=True, help="DIR/<seq>/groundtruth_rect.txt (+ attributes)")
    p.add_argument("--results", required=True, help="DIR/<tracker>/<seq>.txt")
    p.add_argument("--out", required=True, help="folder for ope.json and the PNGs (created)")
    p.add_argument("--convention", choices=ope.CONVENTIONS, default="otb",
                   help="otb: OTB/UAV123 MATLAB toolkit (default); got10k: the got10k Python toolkit")
    p.add_argument("--trackers", help="comma-separated tracker folder names (default: all)")
    p.add_argument("--origin", type=int, choices=(0, 1), default=0,
                   help="coordinate origin of the files: 0 (ours, default) or 1 (OTB/UAV123's); "
                        "only OTB's validity test x>0, y>0 depends on it")
    p.add_argument("--require-all", action="store_true",
                   help="fail if a tracker lacks a sequence (default: warn and skip it there)")
    p.add_argument("--matlab-drop-zero-curves", action="store_true",
                   help="like OTB's plotDrawSave.m, leave all-zero per-sequence curves out of the means")
    return p.parse_args(argv)


def _table(report):
    lines = ["%-24s %8s %8s %5s" % ("tracker", "AUC", "P@20", "seqs")]
    ranked = sorted(report["trackers"].items(), key=lambda kv: -kv[1]["success_auc"])
    for name, t in ranked:
        lines.append("%-24s %8.3f %8.3f %5d" % (name, t["success_auc"], t["precision_20"], t["sequences"]))
    return "\n".join(lines)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    trackers = [t.strip() for t in args.trackers.split(",") if t.strip()] if args.trackers else None
    try:
        report = ope.evaluate(args.sequences, args.results, args.convention, trackers=trackers, origin=args.origin,
                              require_all=args.require_all, drop_zero_curves=args.matlab_drop_zero_curves)
    except ope.OpeError as e:
        print("sim4cv.ope: error: %s" % e, file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    try:
        from . import ope_plots
    except ImportError as e:
        report["plots"] = []
        report["warnings"].append("plots skipped: matplotlib cannot be imported (%s)" % e)
    else:
        report["plots"] = [os.path.basename(p) for p in ope_plots.plot_report(report, args.out)]
    path = os.path.join(args.out, "ope.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(report, f, indent=1, allow_nan=False)
        f.write("\n")
    for w in report["warnings"]:
        print("sim4cv.ope: warning: %s" % w, file=sys.stderr)
    print(_table(report))
    print("wrote %s (%s convention) and %d plots in %s" % (path, args.convention, len(report["plots"]), args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
