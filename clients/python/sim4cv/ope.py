"""One-pass evaluation (OPE) of single-object trackers: success and precision
curves as tracking papers compute them. Pure numpy; plots are in ope_plots.py,
the command line in ope_cli.py (`python3 -m sim4cv.ope --help`). docs/tracking.md,
"Offline evaluation (OPE)", has the same rules with the file formats.

Boxes are rows `x, y, w, h` in pixels. Our generator writes 0-based
coordinates: (0, 0) is the top-left corner of the top-left pixel and a box
covers [x, x+w) x [y, y+h). OTB/UAV123 files are 1-based (the top-left pixel
is (1, 1)); IoU and centre error do not depend on the origin, only OTB's
validity test `x > 0 and y > 0` does (see `origin` below). A row holding a NaN
is read as all-NaN (target not visible / no prediction).

The two conventions, side by side (frame 1 is the first line):

  rule                        | otb (default)                        | got10k
  ----------------------------+--------------------------------------+-------------------------------------
  source                      | OTB toolkit calcSeqErrRobust.m,      | got10k/experiments/otb.py report(),
                              | calcRectInt.m, genPerfMat.m (UAV123  | uav123.py/lasot.py _calc_metrics,
                              | uses the same files)                 | got10k/utils/metrics.py
  frame 1                     | replaced by the ground truth, AFTER  | replaced by the ground truth
                              | the repair below                     | (even if that is NaN)
  invalid prediction (NaN,    | for frames 2..N, in order: replaced  | kept: NaN scores IoU NaN and centre
  w <= 0 or h <= 0)           | by the previous frame's (already     | error NaN (misses); w/h <= 0 scores
                              | repaired) prediction, but only when  | IoU 0 and its centre error is
                              | that frame's ground truth has no NaN | computed as for any box
  valid ground truth          | all four values > 0 in 1-based       | no NaN (zero or negative sizes
                              | coordinates (x > -1, y > -1, w > 0,  | count as valid)
                              | h > 0 in ours, origin=0)             |
  frames with invalid truth   | stay in the denominator with         | removed from the denominator
                              | overlap -1 (a miss at every IoU      |
                              | threshold) and centre error -1,      |
                              | which is <= every distance threshold:|
                              | a HIT on the precision curve         |
  IoU                         | calcRectInt: right = x + w - 1,      | inter / (union + 2.2e-16) with
                              | inter = max(0, min(r) - max(x) + 1)  | inter = max(0, min(x+w) - max(x)),
                              | per axis (= continuous [x, x+w)),    | clipped to [0, 1]
                              | inter / union, no clipping           |
  centre                      | x + (w - 1)/2, y + (h - 1)/2         | same
  success at t                | overlap > t (strict), t = 0:0.05:1   | same (np.linspace(0, 1, 21))
  precision at d              | centre error <= d, d = 0..50 px      | same
  success AUC / precision     | mean of the 21 success values /      | same
                              | precision curve at 20 px             |
  result shorter than truth   | padded with its last line (warning;  | truth cut to the result's length
                              | the MATLAB toolkit would fail)       | (warning), as the toolkit does
  result longer than truth    | cut to the truth's length (warning)  | same
  overall / per attribute     | mean of the per-sequence curves      | same
  sequence with no valid      | (cannot happen: all frames count)    | skipped with a warning (the
  frame                       |                                      | toolkit would average a NaN)

Optional (`drop_zero_curves=True`, CLI --matlab-drop-zero-curves): the OTB
MATLAB plotDrawSave.m leaves out of a tracker's mean every sequence whose
curve sums to 0 (total failure), separately for success and precision.
"""

import math
import os
import re

import numpy as np

CONVENTIONS = ("otb", "got10k", "got10k_otb")
SUCCESS_THRESHOLDS = np.linspace(0.0, 1.0, 21)
PRECISION_THRESHOLDS = np.arange(51, dtype=float)
PRECISION_INDEX = 20  # PRECISION_THRESHOLDS[20] == 20 px
# normalised precision (LaSOT, TrackingNet): centre error in units of the truth's size; reported at 0.2 as
# pytracking's extract_results/plot_results do (thresholds 0, 0.01, ..., 0.5)
NORM_PRECISION_THRESHOLDS = np.arange(51, dtype=float) / 100.0
NORM_PRECISION_INDEX = 20
SR50_INDEX, SR75_INDEX = 10, 15  # SUCCESS_THRESHOLDS[10] == 0.5, [15] == 0.75
_SEPARATORS = re.compile(r"[,\s]+")
_EPS = np.finfo(float).eps


class OpeError(ValueError):
    """A malformed or missing input file; the message names the file (and line)."""


# ----------------------------------------------------------------------------- reading


def read_boxes(path):
    """(N, 4) float array of `x, y, w, h` rows separated by commas, tabs or
    spaces. Empty lines at the end are ignored; any other line that is not
    four numbers raises OpeError naming the file and line. A row with a NaN
    becomes all-NaN."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise OpeError("%s: cannot read: %s" % (path, e.strerror or e)) from None
    while lines and not lines[-1].strip():
        lines.pop()
    rows = []
    for number, line in enumerate(lines, 1):
        fields = [s for s in _SEPARATORS.split(line.strip()) if s]
        try:
            if len(fields) != 4:
                raise ValueError
            row = [float(s) for s in fields]
            if any(math.isinf(v) for v in row):
                raise ValueError
        except ValueError:
            raise OpeError("%s:%d: expected 4 numbers x,y,w,h (comma, tab or space separated, NaN allowed), "
                           "got %r" % (path, number, line)) from None
        rows.append([math.nan] * 4 if any(math.isnan(v) for v in row) else row)
    if not rows:
        raise OpeError("%s: no boxes" % path)
    return np.array(rows, dtype=float)


def read_attribute_names(path):
    """[(ABBREV, full name)] from `ABBREV<TAB>Full name` lines (blank lines skipped)."""
    names = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            parts = line.rstrip("\r\n").split("\t", 1)
            abbrev = parts[0].strip()
            if not abbrev or len(parts) != 2 or not parts[1].strip():
                raise OpeError("%s:%d: expected ABBREV<TAB>Full name, got %r" % (path, number, line.rstrip("\n")))
            names.append((abbrev, parts[1].strip()))
    return names


def _flags(text, path, number, count):
    fields = [s for s in _SEPARATORS.split(text.strip()) if s]
    if len(fields) != count or any(s not in ("0", "1") for s in fields):
        raise OpeError("%s:%d: expected %d comma-separated 0/1 flags, got %r" % (path, number, count, text))
    return [s == "1" for s in fields]


def read_sequence_attributes(seq_dir, names, warnings):
    """{ABBREV: bool} for one sequence: attributes.txt (one line of 0/1 flags in
    the order of `names`) or else attributes_per_frame.csv (header of ABBREVs,
    one 0/1 row per frame; the sequence has an attribute if any frame has it).
    Neither file: no attributes."""
    abbrevs = [a for a, _ in names]
    path = os.path.join(seq_dir, "attributes.txt")
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            lines = [line for line in f.read().splitlines() if line.strip()]
        if len(lines) != 1:
            raise OpeError("%s: expected one line of %d flags, got %d lines" % (path, len(abbrevs), len(lines)))
        return dict(zip(abbrevs, _flags(lines[0], path, 1, len(abbrevs))))
    path = os.path.join(seq_dir, "attributes_per_frame.csv")
    if not os.path.exists(path):
        return {}
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    if not lines:
        raise OpeError("%s: empty" % path)
    header = [s.strip() for s in lines[0].split(",")]
    unknown = [a for a in header if a not in abbrevs]
    if unknown:
        warnings.append("%s: columns not in attribute_names.txt ignored: %s" % (path, ", ".join(unknown)))
    seen = dict.fromkeys(header, False)
    for number, line in enumerate(lines[1:], 2):
        if line.strip():
            for abbrev, flag in zip(header, _flags(line, path, number, len(header))):
                seen[abbrev] = seen[abbrev] or flag
    return {a: seen.get(a, False) for a in abbrevs}


# ----------------------------------------------------------------------------- per-frame maths


def centres(boxes):
    """(N, 2) centres x + (w-1)/2, y + (h-1)/2 (both toolkits' convention)."""
    boxes = np.asarray(boxes, dtype=float)
    return boxes[:, :2] + (boxes[:, 2:] - 1.0) / 2.0


def centre_errors(boxes, truth):
    return np.sqrt(np.sum((centres(boxes) - centres(truth)) ** 2, axis=1))


def normalised_centre_errors(boxes, truth):
    """pytracking's calc_err_center(normalized=True): both centres divided by the truth's (w, h)."""
    truth = np.asarray(truth, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.sum(((centres(boxes) - centres(truth)) / truth[:, 2:]) ** 2, axis=1))


def iou_otb(a, b):
    """calcRectInt.m: right = x + w - 1, intersection max(0, min(right) -
    max(left) + 1) per axis, i.e. the overlap of continuous [x, x+w); no
    clipping, no epsilon (0/0 gives NaN, a miss)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        iw = np.maximum(0.0, np.minimum(a[:, 0] + a[:, 2] - 1, b[:, 0] + b[:, 2] - 1)
                        - np.maximum(a[:, 0], b[:, 0]) + 1)
        ih = np.maximum(0.0, np.minimum(a[:, 1] + a[:, 3] - 1, b[:, 1] + b[:, 3] - 1)
                        - np.maximum(a[:, 1], b[:, 1]) + 1)
        inter = iw * ih
        return inter / (a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter)


def iou_got10k(a, b):
    """got10k/utils/metrics.py rect_iou (no image bound): inter / (union + eps), clipped to [0, 1]."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        iw = np.maximum(np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2]) - np.maximum(a[:, 0], b[:, 0]), 0)
        ih = np.maximum(np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3]) - np.maximum(a[:, 1], b[:, 1]), 0)
        inter = iw * ih
        union = a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter
        return np.clip(inter / (union + _EPS), 0.0, 1.0)


def repair_otb(result, truth):
    """calcSeqErrRobust.m's repair, then frame 1 := ground truth."""
    res = np.array(result, dtype=float)
    truth_has_nan = np.isnan(truth).any(axis=1)
    for i in range(1, len(res)):
        r = res[i]
        if (np.isnan(r).any() or r[2] <= 0 or r[3] <= 0) and not truth_has_nan[i]:
            res[i] = res[i - 1]
    res[0] = truth[0]
    return res


def valid_truth(truth, convention, origin=0):
    truth = np.asarray(truth, dtype=float)
    if convention == "got10k":
        return ~np.isnan(truth).any(axis=1)
    one_based = truth + np.array([1.0 - origin, 1.0 - origin, 0.0, 0.0])
    with np.errstate(invalid="ignore"):
        return (one_based > 0).all(axis=1)  # NaN > 0 is False


def frame_scores(result, truth, convention="otb", origin=0):
    """(overlaps, centre errors) of the frames in the denominator (frame_measures)."""
    m = frame_measures(result, truth, convention, origin)
    return m["overlaps"], m["errors"]


def frame_measures(result, truth, convention="otb", origin=0):
    """{overlaps, errors, normalised errors} of the frames in the denominator:
    every frame for otb (invalid truth: -1, -1, -1, as pytracking scores UAV123)
    and got10k_otb (invalid truth: NaN, a miss everywhere), the frames with
    valid truth for got10k. result and truth must have the same length (align)."""
    result, truth = np.asarray(result, dtype=float), np.asarray(truth, dtype=float)
    if result.shape != truth.shape:
        raise ValueError("result %s and truth %s differ in shape" % (result.shape, truth.shape))
    if convention not in CONVENTIONS:
        raise ValueError("unknown convention %r (expected one of %s)" % (convention, ", ".join(CONVENTIONS)))
    valid = valid_truth(truth, convention, origin)
    if convention == "otb":
        res = repair_otb(result, truth)
        overlaps = -np.ones(len(truth))
        overlaps[valid] = iou_otb(res[valid], truth[valid])
        errors, normalised = centre_errors(res, truth), normalised_centre_errors(res, truth)
        errors[~valid] = normalised[~valid] = -1.0
        return {"overlaps": overlaps, "errors": errors, "normalised": normalised}
    res = result.copy()
    res[0] = truth[0]
    if convention == "got10k":
        res, truth = res[valid], truth[valid]
    # got10k_otb: got10k's ExperimentOTB.report: every frame, rect_iou and center_error as they come (NaN: a miss)
    return {"overlaps": iou_got10k(res, truth), "errors": centre_errors(res, truth),
            "normalised": normalised_centre_errors(res, truth)}


def curves(overlaps, errors):
    """(success curve over SUCCESS_THRESHOLDS: overlap > t, precision curve over
    PRECISION_THRESHOLDS: error <= d), fractions of all frames given; NaN never counts."""
    overlaps, errors = np.asarray(overlaps, dtype=float), np.asarray(errors, dtype=float)
    if len(overlaps) == 0:
        raise ValueError("no frames to score")
    with np.errstate(invalid="ignore"):
        success = np.mean(overlaps[:, None] > SUCCESS_THRESHOLDS[None, :], axis=0)
        precision = np.mean(errors[:, None] <= PRECISION_THRESHOLDS[None, :], axis=0)
    return success, precision


def align(result, truth, convention="otb"):
    """(result, truth, warning or None) of equal length: otb pads a short result
    with its last line, got10k cuts the truth; a long result is cut."""
    n, m = len(truth), len(result)
    if m == n:
        return result, truth, None
    if m > n:
        return result[:n], truth, "result has %d lines, ground truth %d: extra lines ignored" % (m, n)
    if convention == "otb":
        padded = np.vstack([result, np.repeat(result[-1:], n - m, axis=0)])
        return padded, truth, "result has %d lines, ground truth %d: padded with its last line" % (m, n)
    return result, truth[:m], "result has %d lines, ground truth %d: ground truth cut to %d frames" % (m, n, m)


def score(success, precision, normalised=None, average_overlap=None):
    """{success_auc, precision_20, sr_50, sr_75, success_curve, precision_curve}
    of two curves, plus norm_precision_20 and its curve, and ao, when given."""
    out = {"success_auc": float(np.mean(success)), "precision_20": float(precision[PRECISION_INDEX]),
           "sr_50": float(success[SR50_INDEX]), "sr_75": float(success[SR75_INDEX]),
           "success_curve": [float(v) for v in success], "precision_curve": [float(v) for v in precision]}
    if normalised is not None:
        out["norm_precision_20"] = float(normalised[NORM_PRECISION_INDEX])
        out["norm_precision_curve"] = [float(v) for v in normalised]
    if average_overlap is not None:
        out["ao"] = float(average_overlap)
    return out


def evaluate_sequence(result, truth, convention="otb", origin=0):
    """Scores of one sequence: score()'s dict plus "frames" (the denominator).
    ao: the mean overlap over those frames, a frame without one (NaN, or -1
    for invalid truth under otb) counting 0."""
    m = frame_measures(result, truth, convention, origin)
    success, precision = curves(m["overlaps"], m["errors"])
    with np.errstate(invalid="ignore"):
        normalised = np.mean(m["normalised"][:, None] <= NORM_PRECISION_THRESHOLDS[None, :], axis=0)
    overlaps = np.nan_to_num(np.maximum(m["overlaps"], 0.0), nan=0.0)
    out = score(success, precision, normalised, float(np.mean(overlaps)))
    out["frames"] = int(len(m["overlaps"]))
    return out


def average(per_sequence, drop_zero_curves=False):
    """score() of the mean of per-sequence curves (equal weight per sequence).
    drop_zero_curves: leave out curves summing to 0, as OTB's plotDrawSave.m does."""
    def mean_of(key, size):
        rows = np.array([s[key] for s in per_sequence if key in s], dtype=float).reshape(-1, size)
        if drop_zero_curves:
            rows = rows[rows.sum(axis=1) > _EPS]
        return rows.mean(axis=0) if len(rows) else np.zeros(size)
    aos = [s["ao"] for s in per_sequence if "ao" in s]
    out = score(mean_of("success_curve", len(SUCCESS_THRESHOLDS)),
                mean_of("precision_curve", len(PRECISION_THRESHOLDS)),
                mean_of("norm_precision_curve", len(NORM_PRECISION_THRESHOLDS)),
                float(np.mean(aos)) if aos else math.nan)
    out["sequences"] = len(per_sequence)
    return out


# ----------------------------------------------------------------------------- a whole tree


def _subdirs(path):
    return sorted(d for d in os.listdir(path) if os.path.isdir(os.path.join(path, d)))


def evaluate(sequences_dir, results_dir, convention="otb", trackers=None, origin=0,
             require_all=False, drop_zero_curves=False):
    """The ope.json report of every tracker (subfolder of results_dir, or the
    names given) on every sequence (subfolder of sequences_dir with a
    groundtruth_rect.txt). A missing result file is skipped with a warning
    (the tracker's averages then cover fewer sequences; its "skipped" lists
    them), or raises OpeError if require_all."""
    if convention not in CONVENTIONS:
        raise ValueError("unknown convention %r (expected one of %s)" % (convention, ", ".join(CONVENTIONS)))
    for label, path in (("sequences", sequences_dir), ("results", results_dir)):
        if not os.path.isdir(path):
            raise OpeError("%s directory %s does not exist" % (label, path))
    warnings = []
    names_path = os.path.join(sequences_dir, "attribute_names.txt")
    names = read_attribute_names(names_path) if os.path.exists(names_path) else []
    sequences, truths, attributes = [], {}, {}
    for seq in _subdirs(sequences_dir):
        gt_path = os.path.join(sequences_dir, seq, "groundtruth_rect.txt")
        if not os.path.exists(gt_path):
            warnings.append("%s: no groundtruth_rect.txt, not a sequence" % os.path.join(sequences_dir, seq))
            continue
        sequences.append(seq)
        truths[seq] = read_boxes(gt_path)
        attributes[seq] = read_sequence_attributes(os.path.join(sequences_dir, seq), names, warnings) if names else {}
    if not sequences:
        raise OpeError("%s: no sequence folders with a groundtruth_rect.txt" % sequences_dir)
    trackers = list(trackers) if trackers else _subdirs(results_dir)
    if not trackers:
        raise OpeError("%s: no tracker folders" % results_dir)
    absent = [t for t in trackers if not os.path.isdir(os.path.join(results_dir, t))]
    if absent:
        raise OpeError("%s: no folder for tracker(s) %s" % (results_dir, ", ".join(absent)))
    report = {"convention": convention, "origin": origin, "sequences": sequences,
              "success_thresholds": [float(t) for t in SUCCESS_THRESHOLDS],
              "precision_thresholds": [float(t) for t in PRECISION_THRESHOLDS],
              "attributes": {a: {"name": full, "sequences": [s for s in sequences if attributes[s].get(a)]}
                             for a, full in names},
              "trackers": {}, "warnings": warnings}
    for tracker in trackers:
        per_sequence, skipped = {}, []
        for seq in sequences:
            path = os.path.join(results_dir, tracker, seq + ".txt")
            if not os.path.exists(path):
                if require_all:
                    raise OpeError("%s: missing (tracker %s, sequence %s)" % (path, tracker, seq))
                skipped.append(seq)
                warnings.append("%s: missing; tracker %s skipped on sequence %s" % (path, tracker, seq))
                continue
            result, truth, note = align(read_boxes(path), truths[seq], convention)
            if note:
                warnings.append("%s: %s" % (path, note))
            if convention == "got10k" and not valid_truth(truth, convention).any():
                warnings.append("%s: no frame with valid ground truth, sequence skipped" % path)
                skipped.append(seq)
                continue
            per_sequence[seq] = evaluate_sequence(result, truth, convention, origin)
        if not per_sequence:
            warnings.append("tracker %s: no sequence evaluated" % tracker)
        entry = average(list(per_sequence.values()), drop_zero_curves)
        entry["skipped"] = skipped
        entry["per_sequence"] = per_sequence
        entry["per_attribute"] = {}
        for abbrev, _ in names:
            members = [per_sequence[s] for s in sequences if attributes[s].get(abbrev) and s in per_sequence]
            if members:
                entry["per_attribute"][abbrev] = average(members, drop_zero_curves)
        report["trackers"][tracker] = entry
    return report



if __name__ == "__main__":
    import sys
    from sim4cv.ope_cli import main  # the command line lives there; this file is only its -m name
    sys.exit(main())
