"""A model's predicted waypoints beside a dataset's labels, image by image
(docs/driving.md, "Where the network errs"): open loop, to see where in a
turn the network's path goes wrong before asking why the car left the lane.

    python3 -m sim4cv.driving probe --model M --dataset DIR [--map NAME] [--samples A:B] [--lane-only] [--out CSV]

The images go through driving_eval.NetworkPolicy, the closed loop's own
inference (the resize, the goal input), with each row's goal. Prints one
line per image (true and predicted h, predicted v), the mean absolute
error of each h over all rows and over the junction rows, and the error of
h2 (the waypoint the controller steers at) by where the path goes: right
turn, left turn or straight, at a junction or not. --out also writes every
row as CSV.
"""

import argparse
import csv
import os
import sys
from typing import List, Optional, Sequence

from . import driving_eval as de
from .driving_train import TARGETS, TrainError, read_labels  # the model's outputs in order; labels.csv's checks

H, V = tuple(TARGETS[1::2]), tuple(TARGETS[0::2])
TURN_H2_M = 0.3  # |h2| beyond this: the path turns within the controller's 4 m (a radius under about 27 m)


class ProbeError(RuntimeError):
    pass


def parse_samples(text: str):
    """'A:B' -> (A, B), both sample numbers included; '' -> None (all)."""
    if not text:
        return None
    try:
        first, last = (int(part) for part in text.split(":"))
    except ValueError:
        raise ProbeError("--samples %s: expected FIRST:LAST, two sample numbers" % text)
    if first > last:
        raise ProbeError("--samples %s: FIRST is after LAST" % text)
    return first, last


def select(rows: Sequence[dict], map_name: str = "", samples=None, lane_only: bool = False) -> List[dict]:
    """The labels.csv rows of one map (all maps: ''), samples FIRST..LAST, and
    with lane_only the lane views only (no offset, no turn)."""
    out = []
    for r in rows:
        if map_name and r["map"] != map_name:
            continue
        if samples and not samples[0] <= int(r["sample"]) <= samples[1]:
            continue
        if lane_only and (float(r["offset_side_m"]) != 0.0 or float(r["offset_yaw_deg"]) != 0.0):
            continue
        out.append(r)
    return out


def probe(policy, dataset: str, rows: Sequence[dict]) -> dict:
    """Runs `policy` (a NetworkPolicy) on each row's image: {"rows": [...],
    "mae_h": {h: m}, "mae_h_junction": {h: m}, "h2_by_group": {group: {...}}, "images": n}."""
    import cv2
    results = []
    for r in rows:
        path = os.path.join(dataset, r["image"])
        image = cv2.imread(path, cv2.IMREAD_COLOR)
        if image is None:
            raise ProbeError("%s: not readable as an image (labels.csv names it)" % path)
        policy.goal = float(r.get("goal", 0) or 0)
        out = policy.waypoints(cv2.cvtColor(image, cv2.COLOR_BGR2RGB), None, None)
        row = dict(r)
        row.update({"pred_" + k: value for k, value in zip(TARGETS, out)})
        results.append(row)

    def mae(subset):
        if not subset:
            return None
        return {h: sum(abs(float(x[h]) - x["pred_" + h]) for x in subset) / len(subset) for h in H}
    groups = {}
    for x in results:
        groups.setdefault(group(x), []).append(float(x["pred_h2"]) - float(x["h2"]))
    return {"rows": results, "images": len(results), "mae_h": mae(results),
            "mae_h_junction": mae([x for x in results if _at_junction(x)]),
            "h2_by_group": {g: {"images": len(e), "mean_error_m": sum(e) / len(e),
                                "mean_abs_error_m": sum(abs(v) for v in e) / len(e)}
                            for g, e in sorted(groups.items())}}


def group(row: dict) -> str:
    """Where the labelled path goes at the second waypoint (the one the
    controller steers at): 'right turn', 'left turn' (|h2| > TURN_H2_M) or
    'straight', with ' at junction' for relabel's junction rows. Meant for
    lane views (--lane-only): an offset view's h holds its offset too."""
    h2 = float(row["h2"])
    name = "right turn" if h2 > TURN_H2_M else "left turn" if h2 < -TURN_H2_M else "straight"
    return name + (" at junction" if _at_junction(row) else "")


def _at_junction(row: dict) -> bool:
    return str(row.get("junction", "0")) == "1"  # relabel's column; absent before relabel


def _line(row: dict) -> str:
    return ("%s sample %5s view (%8.2f, %8.2f, %7.1f) offset %5.2f m %6.1f deg goal %2s | h true %s | pred %s | v %s"
            % (row["map"], row["sample"], float(row["view_x"]), float(row["view_y"]), float(row["view_yaw_deg"]),
               float(row["offset_side_m"]), float(row["offset_yaw_deg"]), row.get("goal", "0"),
               " ".join("%5.2f" % float(row[h]) for h in H), " ".join("%5.2f" % row["pred_" + h] for h in H),
               " ".join("%4.1f" % row["pred_" + v] for v in V)))


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving probe",
                                description="a model's waypoints beside a dataset's labels, image by image")
    p.add_argument("--model", required=True, help="model.pt or model.onnx")
    p.add_argument("--dataset", required=True, help="a dataset folder (holds labels.csv)")
    p.add_argument("--map", default="", help="only this map's rows (its name, e.g. driving_val_02_desert)")
    p.add_argument("--samples", default="", help="FIRST:LAST sample numbers (both included)")
    p.add_argument("--lane-only", action="store_true", help="only the lane views (no offset, no turn)")
    p.add_argument("--out", help="write every row, labels and predictions, to this CSV file")
    a = p.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        rows = select(read_labels(a.dataset), a.map, parse_samples(a.samples), a.lane_only)
        if not rows:
            raise ProbeError("no row of %s/labels.csv matches --map %r --samples %r%s"
                             % (a.dataset, a.map, a.samples, " --lane-only" if a.lane_only else ""))
        result = probe(de.NetworkPolicy(a.model), a.dataset, rows)
    except (ProbeError, TrainError, de.EvalError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    for row in result["rows"]:
        print(_line(row))
    for name in ("mae_h", "mae_h_junction"):
        if result[name]:
            print("%s: %s" % (name, " ".join("%s %.3f m" % (h, m) for h, m in result[name].items())))
    for g, e in result["h2_by_group"].items():
        print("h2 %s: %d images, mean error %+.3f m (positive: right of the label), mean absolute error %.3f m"
              % (g, e["images"], e["mean_error_m"], e["mean_abs_error_m"]))
    if a.out:
        with open(a.out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(result["rows"][0]))
            w.writeheader()
            w.writerows(result["rows"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
