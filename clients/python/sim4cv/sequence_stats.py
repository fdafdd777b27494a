"""The statistics that make a tracking benchmark hard, per sequence set:
where the target sits in the image, how much its scale and aspect change,
how often it is cut by the frame edge or out of view, and how many frames
carry each attribute.

    python3 -m sim4cv.sequences stats DIR [--json OUT.json]

Reads only the generated folders (groundtruth_rect.txt, sequence.json,
attributes_per_frame.csv, attribute_names.txt); docs/tracking.md, "Camera
motion".
"""

import csv
import json
import os

import numpy as np

from .ope import read_boxes

PERCENTILES = (10, 50, 90)


def _percentiles(values):
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"mean": None, **{"p%d" % p: None for p in PERCENTILES}}
    out = {"mean": round(float(values.mean()), 4)}
    out.update({"p%d" % p: round(float(np.percentile(values, p)), 4) for p in PERCENTILES})
    return out


def _attribute_frames(seq_dir):
    path = os.path.join(seq_dir, "attributes_per_frame.csv")
    if not os.path.isfile(path):
        return {}
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], np.array(rows[1:], dtype=int) if len(rows) > 1 else np.zeros((0, len(rows[0])), int)
    return {name: int(body[:, i].sum()) for i, name in enumerate(header)}


def sequence_measures(seq_dir):
    """Per-frame arrays of one sequence: centre offset (fraction of the
    half-diagonal), scale and aspect relative to the first frame, absent."""
    meta = json.load(open(os.path.join(seq_dir, "sequence.json"), encoding="utf-8"))
    width, height = meta["image_size"]
    gt = read_boxes(os.path.join(seq_dir, "groundtruth_rect.txt"))
    valid = np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
    centre = gt[:, :2] + gt[:, 2:] / 2.0
    offset = np.hypot(centre[:, 0] - width / 2.0, centre[:, 1] - height / 2.0) / np.hypot(width / 2.0, height / 2.0)
    first = gt[np.argmax(valid)]
    scale = np.sqrt(gt[:, 2] * gt[:, 3] / (first[2] * first[3]))
    aspect = (gt[:, 2] / gt[:, 3]) / (first[2] / first[3])
    cut = valid & ((gt[:, 0] <= 0) | (gt[:, 1] <= 0) | (gt[:, 0] + gt[:, 2] >= width) | (gt[:, 1] + gt[:, 3] >= height))
    return {"offset": np.where(valid, offset, np.nan), "scale": np.where(valid, scale, np.nan),
            "aspect": np.where(valid, aspect, np.nan), "absent": ~valid, "cut": cut,
            "camera_motion": meta.get("camera_motion", "servo"), "frames": len(gt)}


def set_statistics(root):
    """The statistics of every complete sequence under root, pooled over frames
    and per sequence."""
    names = sorted(d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "sequence.json"))
                   and os.path.isfile(os.path.join(root, d, "groundtruth_rect.txt")))
    pooled = {k: [] for k in ("offset", "scale", "aspect")}
    absent = cut = frames = 0
    attributes, per_sequence = {}, {}
    for name in names:
        seq_dir = os.path.join(root, name)
        m = sequence_measures(seq_dir)
        for k in pooled:
            pooled[k].append(m[k])
        absent += int(m["absent"].sum())
        cut += int(m["cut"].sum())
        frames += m["frames"]
        counts = _attribute_frames(seq_dir)
        for a, n in counts.items():
            attributes[a] = attributes.get(a, 0) + n
        per_sequence[name] = {"frames": m["frames"], "camera_motion": m["camera_motion"],
                              "absent_frames": int(m["absent"].sum()), "cut_frames": int(m["cut"].sum()),
                              "offset_median": _percentiles(m["offset"])["p50"],
                              "scale_range": [round(float(np.nanmin(m["scale"])), 3),
                                              round(float(np.nanmax(m["scale"])), 3)],
                              "attribute_frames": counts}
    joined = {k: np.concatenate(v) if v else np.zeros(0) for k, v in pooled.items()}
    return {"sequences": len(names), "frames": frames,
            "centre_offset_of_half_diagonal": _percentiles(joined["offset"]),
            "scale_change": _percentiles(joined["scale"]),
            "scale_change_outside_0.5_2": _fraction(joined["scale"], 0.5 ** 0.5, 2 ** 0.5),
            "aspect_change": _percentiles(joined["aspect"]),
            "aspect_change_outside_0.5_2": _fraction(joined["aspect"], 0.5, 2),
            "fraction_target_absent": round(absent / max(frames, 1), 4),
            "fraction_cut_by_frame_edge": round(cut / max(frames, 1), 4),
            "attribute_frames": attributes, "per_sequence": per_sequence}


def _fraction(values, lo, hi):
    """Fraction of the valid frames outside [lo, hi] (scale: of the side, so area outside [0.5, 2])."""
    values = values[np.isfinite(values)]
    return round(float(np.mean((values < lo) | (values > hi))), 4) if values.size else None


def markdown(stats):
    """A short table of the pooled figures."""
    o, s, a = stats["centre_offset_of_half_diagonal"], stats["scale_change"], stats["aspect_change"]
    lines = ["| measure | mean | p10 | p50 | p90 |", "|---|---|---|---|---|"]
    for label, d in (("centre offset / half-diagonal", o), ("scale (sqrt area / first)", s),
                     ("aspect (w/h / first)", a)):
        lines.append("| %s | %s | %s | %s | %s |" % (label, d["mean"], d["p10"], d["p50"], d["p90"]))
    lines += ["", "%d sequences, %d frames; target absent %.1f %%, cut by the frame edge %.1f %%; "
              "area outside [0.5, 2] x the first %.1f %%; aspect outside [0.5, 2] x the first %.1f %%"
              % (stats["sequences"], stats["frames"], 100 * stats["fraction_target_absent"],
                 100 * stats["fraction_cut_by_frame_edge"], 100 * (stats["scale_change_outside_0.5_2"] or 0),
                 100 * (stats["aspect_change_outside_0.5_2"] or 0)),
              "", "frames per attribute: " + ", ".join("%s %d" % kv for kv in stats["attribute_frames"].items())]
    return "\n".join(lines)
