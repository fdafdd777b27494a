"""Generated sequences and tracker results in the folder layouts the field's
toolkits read as they are (no symlinks, no renaming by hand):

    python3 -m sim4cv.sequences export DIR --format uav123|got10k|otb --out OUT
    python3 -m sim4cv.sequences export-results RESULTS --layout got10k|pytracking --out OUT

Boxes are written 1-based (the top-left pixel is (1, 1)), as the MATLAB
toolkits and the datasets' own annotations number them; our files are
0-based. NaN rows stay NaN (UAV123's convention for a target fully occluded
or out of the frame).

  uav123   OUT/data_seq/UAV123/<seq>/000001.jpg ...
           OUT/anno/UAV123/<seq>.txt           x,y,w,h per frame
           OUT/anno/UAV123/att/<seq>.txt       UAV123's 12 flags, comma-separated, in its order
           OUT/anno/UAV123/absent/<seq>.txt    ours beside them: 0/1 per frame, 1 = no visible pixel
  got10k   OUT/val/list.txt, OUT/val/<seq>/00000001.jpg ..., groundtruth.txt, absence.label,
           cover.label (0 = fully occluded ... 8 = fully visible), cut_by_image.label, meta_info.ini
  otb      OUT/<seq>/img/0001.jpg ..., OUT/<seq>/groundtruth_rect.txt

Images are hard links to the generated JPEGs where the file system allows
(copies otherwise). Result layouts: got10k `OUT/<tracker>/<seq>.txt`
(comma-separated) and `OUT/<tracker>/times/<seq>_time.txt`; pytracking
`OUT/<tracker>/<seq>.txt` (tab-separated) and `OUT/<tracker>/<seq>_time.txt`.
"""

import csv
import glob
import math
import os
import shutil

import numpy as np

from . import attributes as attrs
from .ope import read_boxes

FORMATS = ("uav123", "got10k", "otb")
RESULT_LAYOUTS = ("got10k", "pytracking")
UAV123_ATTRIBUTES = ("SV", "ARC", "LR", "FM", "FOC", "POC", "OV", "BC", "IV", "VC", "CM", "SOB")
GOT10K_SUBSET = "val"  # the subset whose loader returns every frame's box and the meta labels


class ExportError(RuntimeError):
    pass


def _link(src, dst):
    try:
        os.link(src, dst)
    except OSError:
        shutil.copyfile(src, dst)


def one_based(boxes):
    out = np.array(boxes, dtype=float, copy=True)
    out[:, :2] += 1.0
    return out


def box_lines(boxes, delimiter=","):
    """Rows as text: whole numbers without decimals, NaN rows as NaN."""
    lines = []
    for row in boxes:
        if not np.all(np.isfinite(row)):
            lines.append(delimiter.join(["NaN"] * 4))
        else:
            lines.append(delimiter.join(("%d" % v) if float(v).is_integer() else ("%.3f" % v) for v in row))
    return "\n".join(lines) + "\n"


def _sequences(root):
    names = sorted(d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "groundtruth_rect.txt")))
    if not names:
        raise ExportError("no sequences (folders with groundtruth_rect.txt) in %s" % root)
    return names


def _images(seq_dir):
    images = sorted(glob.glob(os.path.join(seq_dir, "img", "*.jpg")))
    if not images:
        raise ExportError("no img/*.jpg in %s" % seq_dir)
    return images


def _write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def _per_frame(seq_dir, column):
    path = os.path.join(seq_dir, "attributes_per_frame.csv")
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return np.array([int(r[rows[0].index(column)]) for r in rows[1:]], dtype=int)


def _sequence_flags(seq_dir):
    names = attrs.ABBREVS
    with open(os.path.join(seq_dir, "attributes.txt"), encoding="utf-8") as f:
        values = [int(v) for v in f.read().strip().split(",")]
    return dict(zip(names, values))


def export_uav123(root, out):
    for seq in _sequences(root):
        seq_dir = os.path.join(root, seq)
        images = _images(seq_dir)
        dst = os.path.join(out, "data_seq", "UAV123", seq)
        os.makedirs(dst, exist_ok=True)
        for i, image in enumerate(images, 1):
            _link(image, os.path.join(dst, "%06d.jpg" % i))
        truth = read_boxes(os.path.join(seq_dir, "groundtruth_rect.txt"))
        _write(os.path.join(out, "anno", "UAV123", seq + ".txt"), box_lines(one_based(truth)))
        flags = _sequence_flags(seq_dir)
        _write(os.path.join(out, "anno", "UAV123", "att", seq + ".txt"),
               ",".join(str(flags.get(a, 0)) for a in UAV123_ATTRIBUTES) + "\n")
        absent = ~np.all(np.isfinite(truth), axis=1)
        _write(os.path.join(out, "anno", "UAV123", "absent", seq + ".txt"), "".join("%d\n" % v for v in absent))


def cover_levels(visibility):
    """GOT-10k's cover label: 0 = fully occluded, 1..8 = visible fraction in eighths (rounded up)."""
    v = np.clip(np.nan_to_num(np.asarray(visibility, dtype=float)), 0.0, 1.0)
    return np.where(v > 0, np.clip(np.ceil(v * 8 - 1e-9), 1, 8), 0).astype(int)


def export_got10k(root, out):
    import json
    base = os.path.join(out, GOT10K_SUBSET)
    names = _sequences(root)
    for seq in names:
        seq_dir = os.path.join(root, seq)
        images = _images(seq_dir)
        dst = os.path.join(base, seq)
        os.makedirs(dst, exist_ok=True)
        for i, image in enumerate(images, 1):
            _link(image, os.path.join(dst, "%08d.jpg" % i))
        truth = read_boxes(os.path.join(seq_dir, "groundtruth_rect.txt"))
        _write(os.path.join(dst, "groundtruth.txt"), box_lines(one_based(truth)))
        absent = ~np.all(np.isfinite(truth), axis=1)
        _write(os.path.join(dst, "absence.label"), "".join("%d\n" % v for v in absent))
        with open(os.path.join(seq_dir, "poses.csv"), encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        visibility = [float(r["target_visibility"]) for r in rows]
        _write(os.path.join(dst, "cover.label"), "".join("%d\n" % v for v in cover_levels(visibility)))
        _write(os.path.join(dst, "cut_by_image.label"), "".join("%d\n" % v for v in _per_frame(seq_dir, "OV")))
        meta = json.load(open(os.path.join(seq_dir, "sequence.json"), encoding="utf-8"))
        width, height = meta["image_size"]
        info = [("url", "sim4cv:%s" % meta.get("map", "")), ("begin_frame", 1), ("end_frame", len(images)),
                ("object_class", "car"), ("motion_class", "driving"), ("major_class", "motor vehicle"),
                ("root_class", "object"), ("motion_adverb", "fast" if meta.get("speed", 0) >= 6 else "slowly"),
                ("resolution", "(%d, %d)" % (width, height))]
        _write(os.path.join(dst, "meta_info.ini"), "[METAINFO]\n" + "".join("%s: %s\n" % kv for kv in info))
    _write(os.path.join(base, "list.txt"), "\n".join(names) + "\n")


def export_otb(root, out):
    for seq in _sequences(root):
        seq_dir = os.path.join(root, seq)
        images = _images(seq_dir)
        digits = max(4, len(str(len(images))))
        dst = os.path.join(out, seq, "img")
        os.makedirs(dst, exist_ok=True)
        for i, image in enumerate(images, 1):
            _link(image, os.path.join(dst, "%0*d.jpg" % (digits, i)))
        truth = read_boxes(os.path.join(seq_dir, "groundtruth_rect.txt"))
        _write(os.path.join(out, seq, "groundtruth_rect.txt"), box_lines(one_based(truth)))


def export(root, fmt, out):
    """Writes the sequences under `root` in `fmt`'s layout under `out`."""
    writers = {"uav123": export_uav123, "got10k": export_got10k, "otb": export_otb}
    if fmt not in writers:
        raise ExportError("unknown format %r (choose from %s)" % (fmt, ", ".join(FORMATS)))
    os.makedirs(out, exist_ok=True)
    writers[fmt](root, out)


def export_results(results, layout, out):
    """Our results (RESULTS/<tracker>/<seq>.txt + <seq>_time.txt, 0-based) in
    got10k's or pytracking's layout, 1-based."""
    if layout not in RESULT_LAYOUTS:
        raise ExportError("unknown layout %r (choose from %s)" % (layout, ", ".join(RESULT_LAYOUTS)))
    trackers = sorted(d for d in os.listdir(results) if os.path.isdir(os.path.join(results, d)))
    if not trackers:
        raise ExportError("no tracker folders in %s" % results)
    delimiter = "," if layout == "got10k" else "\t"
    for tracker in trackers:
        for path in sorted(glob.glob(os.path.join(results, tracker, "*.txt"))):
            if path.endswith("_time.txt"):
                continue
            seq = os.path.basename(path)[:-4]
            boxes = one_based(read_boxes(path))
            _write(os.path.join(out, tracker, seq + ".txt"), box_lines(boxes, delimiter))
            times = os.path.join(results, tracker, seq + "_time.txt")
            if os.path.isfile(times):
                where = (os.path.join(out, tracker, "times", seq + "_time.txt") if layout == "got10k"
                         else os.path.join(out, tracker, seq + "_time.txt"))
                os.makedirs(os.path.dirname(where), exist_ok=True)
                shutil.copyfile(times, where)
    return trackers


def per_frame_fps(times):
    """got10k's speed of one sequence: the mean of 1/t over the frames with t > 0 (not frames / total time)."""
    t = np.asarray(times, dtype=float)
    t = t[np.isfinite(t) & (t > 0)]
    return float(np.mean(1.0 / t)) if t.size else math.nan
