"""Tracking attributes of a sequence from its ground truth: UAV123's twelve
(Mueller, Smith, Ghanem, "A Benchmark and Simulator for UAV Tracking", ECCV
2016) plus TA (target absent), per frame and per sequence. Pure numpy over
arrays: the ground-truth boxes, the daemon's visibility, the poses and a few
per-frame image measures (box_measures() computes them from an RGB frame).

docs/tracking.md, "Sequences and attributes", has the table of definitions and
thresholds; THRESHOLDS below holds the numbers. sim4cv.sequences writes the
inputs (groundtruth_rect.txt, poses.csv, measures.csv) and the outputs
(attribute_names.txt, attributes.txt, attributes_per_frame.csv) that
`python3 -m sim4cv.ope` reads; attributes_of_sequence(seq_dir) recomputes them
from the files alone.

Boxes are rows `x, y, w, h` in 0-based pixels (a box covers [x, x+w) x
[y, y+h)); a row with a NaN means no box (the target has no visible pixel).
"""

import csv
import math
import os

import numpy as np

# (ABBREV, full name) in the order of attribute_names.txt and of the flags.
ATTRIBUTES = [
    ("SV", "Scale Variation"),
    ("ARC", "Aspect Ratio Change"),
    ("LR", "Low Resolution"),
    ("FM", "Fast Motion"),
    ("FOC", "Full Occlusion"),
    ("POC", "Partial Occlusion"),
    ("OV", "Out-of-View"),
    ("BC", "Background Clutter"),
    ("IV", "Illumination Variation"),
    ("VC", "Viewpoint Change"),
    ("CM", "Camera Motion"),
    ("SOB", "Similar Object"),
    ("TA", "Target Absent"),
]
ABBREVS = [a for a, _ in ATTRIBUTES]

THRESHOLDS = {
    "sv_range": (0.5, 2.0),         # SV: box area / reference area outside this (UAV123)
    "arc_range": (0.5, 2.0),        # ARC: aspect ratio / reference aspect ratio outside this (UAV123)
    "lr_pixels": 400.0,             # LR: box area w*h below this (UAV123)
    "fm_pixels": 20.0,              # FM: centre moved more than this since the previous frame (UAV123)
    "poc_visibility": 0.9,          # POC: 0 < visibility < this
    "ov_margin": 0.0,               # OV: box within this many pixels of an image edge (0: touching it)
    "bc_similarity": 0.45,          # BC: colour-histogram similarity of box and surround above this
    "iv_ratio": 1.5,                # IV: box brightness / reference outside [1/this, this]
    "iv_presets": ("dusk", "night"),  # IV: every frame under these lighting conditions
    "vc_degrees": 30.0,             # VC: direction target->camera (target's frame) turned more than this
    "cm_degrees_per_s": 30.0,       # CM: camera turned faster than this (degrees per second)
    "sob_distance": 2.0,            # SOB: another same-class box's centre within this many target sizes
}

# A sequence has an attribute when at least this fraction of its frames has
# it; 0 means "in at least one frame" (UAV123's rule for SV, ARC, LR, FM).
SEQUENCE_MIN_FRACTION = {
    "SV": 0.0, "ARC": 0.0, "LR": 0.0, "FM": 0.0, "FOC": 0.0, "POC": 0.05, "OV": 0.0,
    "BC": 0.05, "IV": 0.05, "VC": 0.05, "CM": 0.05, "SOB": 0.02, "TA": 0.0,
}

HISTOGRAM_BINS = 4  # per RGB channel, for BC


# ----------------------------------------------------------------------------- helpers


def _boxes(gt):
    gt = np.asarray(gt, dtype=float).reshape(-1, 4)
    valid = ~np.isnan(gt).any(axis=1) & (np.nan_to_num(gt[:, 2]) > 0) & (np.nan_to_num(gt[:, 3]) > 0)
    return gt, valid


def _reference(values, valid):
    """The value of the first valid frame (NaN if none)."""
    idx = np.flatnonzero(valid)
    return values[idx[0]] if len(idx) else math.nan


def _outside(ratio, lo, hi):
    with np.errstate(invalid="ignore"):
        return (ratio < lo) | (ratio > hi)


def centres(gt):
    """(N, 2) box centres x + w/2, y + h/2 (continuous coordinates)."""
    gt = np.asarray(gt, dtype=float).reshape(-1, 4)
    return gt[:, :2] + gt[:, 2:] / 2.0


def yaw_of(qw, qx, qy, qz):
    """Heading (radians, 0 = east, counter-clockwise) of a body->world
    quaternion: atan2 of the body x axis' world y and x (docs/protocol.md 9)."""
    return np.arctan2(2.0 * (np.asarray(qw) * qz + np.asarray(qx) * qy),
                      1.0 - 2.0 * (np.asarray(qy) ** 2 + np.asarray(qz) ** 2))


# ----------------------------------------------------------------------------- per-frame image measures


def box_measures(rgb, box, target_mask=None):
    """(luma, bc_similarity) of one frame for the box (x, y, w, h) or None.

    The target's pixels: those of `target_mask` (a boolean (h, w) array, the
    instance mask == the target's id) inside the box, or the whole box
    without a mask. The surround: the box grown by half its width and height
    on each side, minus the box, clipped to the image.
    luma: mean Y = 0.299 R + 0.587 G + 0.114 B of the target's pixels (0-255).
    bc_similarity: Bhattacharyya coefficient (0: disjoint, 1: identical)
    between the 4x4x4-bin RGB histograms of the target's pixels and of the
    surround. NaN, NaN without a box (NaN similarity without surround pixels)."""
    if box is None or any(math.isnan(v) for v in box) or box[2] <= 0 or box[3] <= 0:
        return math.nan, math.nan
    rgb = np.asarray(rgb)
    h_img, w_img = rgb.shape[:2]
    x0, y0 = int(math.floor(box[0])), int(math.floor(box[1]))
    x1, y1 = int(math.ceil(box[0] + box[2])), int(math.ceil(box[1] + box[3]))
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(w_img, x1), min(h_img, y1)
    if x1 <= x0 or y1 <= y0:
        return math.nan, math.nan
    inner = rgb[y0:y1, x0:x1]
    if target_mask is not None:
        own = np.asarray(target_mask, dtype=bool)[y0:y1, x0:x1]
        inner = inner[own] if own.any() else inner.reshape(-1, 3)
    inner = inner.reshape(-1, 3).astype(np.float64)
    luma = float(np.mean(inner @ np.array([0.299, 0.587, 0.114])))
    gx, gy = int(math.ceil(box[2] / 2.0)), int(math.ceil(box[3] / 2.0))
    ox0, oy0, ox1, oy1 = max(0, x0 - gx), max(0, y0 - gy), min(w_img, x1 + gx), min(h_img, y1 + gy)
    outer = rgb[oy0:oy1, ox0:ox1]
    keep = np.ones(outer.shape[:2], dtype=bool)
    keep[y0 - oy0:y1 - oy0, x0 - ox0:x1 - ox0] = False
    ring = outer[keep].reshape(-1, 3)
    if len(ring) == 0:
        return luma, math.nan
    return luma, histogram_similarity(inner, ring)


def histogram_similarity(pixels_a, pixels_b, bins=HISTOGRAM_BINS):
    """Bhattacharyya coefficient of the joint RGB histograms (bins per channel) of two (n, 3) pixel lists."""
    def hist(p):
        q = (np.asarray(p, dtype=np.int64) * bins) // 256
        h = np.bincount((q[:, 0] * bins + q[:, 1]) * bins + q[:, 2], minlength=bins ** 3).astype(float)
        return h / max(h.sum(), 1.0)
    return float(np.sum(np.sqrt(hist(pixels_a) * hist(pixels_b))))


def similar_object_distance(target_box, other_boxes):
    """Smallest centre distance from the target box to another box (same
    class), in target sizes max(w, h); NaN if there is no other box or no target box."""
    if target_box is None or any(math.isnan(v) for v in target_box):
        return math.nan
    others = np.asarray(other_boxes, dtype=float).reshape(-1, 4)
    if len(others) == 0:
        return math.nan
    size = max(target_box[2], target_box[3], 1e-9)
    c = np.array([target_box[0] + target_box[2] / 2.0, target_box[1] + target_box[3] / 2.0])
    d = np.hypot(*(centres(others) - c).T)
    return float(np.min(d) / size)


# ----------------------------------------------------------------------------- the attributes, per frame


def scale_variation(gt, lo_hi=None):
    lo, hi = lo_hi or THRESHOLDS["sv_range"]
    gt, valid = _boxes(gt)
    area = gt[:, 2] * gt[:, 3]
    return valid & _outside(area / _reference(area, valid), lo, hi)


def aspect_ratio_change(gt, lo_hi=None):
    lo, hi = lo_hi or THRESHOLDS["arc_range"]
    gt, valid = _boxes(gt)
    with np.errstate(invalid="ignore", divide="ignore"):
        aspect = gt[:, 2] / gt[:, 3]
    return valid & _outside(aspect / _reference(aspect, valid), lo, hi)


def low_resolution(gt, pixels=None):
    pixels = THRESHOLDS["lr_pixels"] if pixels is None else pixels
    gt, valid = _boxes(gt)
    with np.errstate(invalid="ignore"):
        return valid & (gt[:, 2] * gt[:, 3] < pixels)


def fast_motion(gt, pixels=None):
    pixels = THRESHOLDS["fm_pixels"] if pixels is None else pixels
    gt, valid = _boxes(gt)
    out = np.zeros(len(gt), dtype=bool)
    if len(gt) > 1:
        c = centres(gt)
        moved = np.hypot(*(c[1:] - c[:-1]).T)
        with np.errstate(invalid="ignore"):
            out[1:] = valid[1:] & valid[:-1] & (moved > pixels)
    return out


def _in_view(in_view, n):
    return np.ones(n, dtype=bool) if in_view is None else np.asarray(in_view, dtype=bool).reshape(n)


def full_occlusion(gt, visibility=None, in_view=None):
    """No visible pixel (visibility 0 / no box) while the target's projection overlaps the image."""
    gt, valid = _boxes(gt)
    vis = np.where(valid, 1.0, 0.0) if visibility is None else np.nan_to_num(np.asarray(visibility, float))
    return (~valid | (vis <= 0.0)) & _in_view(in_view, len(gt))


def partial_occlusion(gt, visibility, threshold=None):
    threshold = THRESHOLDS["poc_visibility"] if threshold is None else threshold
    gt, valid = _boxes(gt)
    vis = np.nan_to_num(np.asarray(visibility, dtype=float))
    return valid & (vis > 0.0) & (vis < threshold)


def out_of_view(gt, image_size, in_view=None, margin=None):
    """The box touches an image edge (part of the target is cut off), or the target is wholly out of the view."""
    margin = THRESHOLDS["ov_margin"] if margin is None else margin
    width, height = image_size
    gt, valid = _boxes(gt)
    with np.errstate(invalid="ignore"):
        edge = ((gt[:, 0] <= margin) | (gt[:, 1] <= margin) | (gt[:, 0] + gt[:, 2] >= width - margin)
                | (gt[:, 1] + gt[:, 3] >= height - margin))
    return (valid & edge) | ~_in_view(in_view, len(gt))


def background_clutter(gt, bc_similarity, threshold=None):
    threshold = THRESHOLDS["bc_similarity"] if threshold is None else threshold
    gt, valid = _boxes(gt)
    with np.errstate(invalid="ignore"):
        return valid & (np.asarray(bc_similarity, dtype=float) > threshold)


def illumination_variation(gt, luma, conditions=None, ratio=None, change_every=0):
    """Box brightness / the first valid frame's outside [1/ratio, ratio]; every
    frame under a dark preset (THRESHOLDS["iv_presets"]); with conditions that
    change every `change_every` frames (domain randomisation), the frames where they change."""
    ratio = THRESHOLDS["iv_ratio"] if ratio is None else ratio
    gt, valid = _boxes(gt)
    luma = np.asarray(luma, dtype=float)
    ok = valid & ~np.isnan(luma)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = ok & _outside(luma / max(_reference(luma, ok), 1.0), 1.0 / ratio, ratio)
    if conditions in THRESHOLDS["iv_presets"]:
        out[:] = True
    if change_every:
        out[change_every::change_every] = True  # frame k*N+1 (1-based) is the first under new conditions
    return out


def view_directions(camera_positions, target_positions, target_yaws):
    """(N, 3) unit vectors from the target to the camera in the target's
    heading frame (x forward, y left, z up)."""
    d = np.asarray(camera_positions, float).reshape(-1, 3) - np.asarray(target_positions, float).reshape(-1, 3)
    c, s = np.cos(target_yaws), np.sin(target_yaws)
    local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return local / np.linalg.norm(local, axis=1, keepdims=True)


def viewpoint_change(camera_positions, target_positions, target_yaws, valid=None, degrees=None):
    """The direction target -> camera, in the target's heading frame, turned more
    than `degrees` from that of the first frame (the first frame with a box if
    `valid` is given)."""
    degrees = THRESHOLDS["vc_degrees"] if degrees is None else degrees
    v = view_directions(camera_positions, target_positions, target_yaws)
    ok = ~np.isnan(v).any(axis=1)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    idx = np.flatnonzero(ok)
    if not len(idx):
        return np.zeros(len(v), dtype=bool)
    angle = np.degrees(np.arccos(np.clip(v @ v[idx[0]], -1.0, 1.0)))
    with np.errstate(invalid="ignore"):
        return ~np.isnan(v).any(axis=1) & (angle > degrees)


def camera_motion(camera_quats, frame_hz, degrees_per_s=None):
    """The camera turned faster than degrees_per_s since the previous frame
    (the rotation angle between consecutive camera orientations times the frame rate)."""
    degrees_per_s = THRESHOLDS["cm_degrees_per_s"] if degrees_per_s is None else degrees_per_s
    q = np.asarray(camera_quats, float).reshape(-1, 4)
    out = np.zeros(len(q), dtype=bool)
    if len(q) < 2:
        return out
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    dot = np.abs(np.sum(q[1:] * q[:-1], axis=1))
    turn = np.degrees(2.0 * np.arccos(np.clip(dot, 0.0, 1.0))) * frame_hz
    with np.errstate(invalid="ignore"):
        out[1:] = turn > degrees_per_s
    return out


def similar_object(gt, sob_distance, threshold=None):
    threshold = THRESHOLDS["sob_distance"] if threshold is None else threshold
    gt, valid = _boxes(gt)
    with np.errstate(invalid="ignore"):
        return valid & (np.asarray(sob_distance, dtype=float) < threshold)


def target_absent(gt):
    return ~_boxes(gt)[1]


def size_boxes(gt, extent=None):
    """The boxes SV, ARC and LR measure: the target's extent as if nothing
    occluded it (`extent`, the projected 3D box) where it is given and the
    frame has a ground-truth box, else the ground-truth box; NaN without a
    ground-truth box."""
    gt, valid = _boxes(gt)
    if extent is None:
        return gt
    ext, ext_valid = _boxes(extent)
    out = np.where((valid & ext_valid)[:, None], ext, gt)
    out[~valid] = np.nan
    return out


def per_frame(gt, image_size, visibility=None, in_view=None, extent=None, luma=None, bc_similarity=None,
              sob_distance=None, camera_positions=None, camera_quats=None, target_positions=None,
              target_yaws=None, frame_hz=30.0, conditions=None, change_every=0):
    """{ABBREV: (N,) bool} for every attribute of ATTRIBUTES (SV, ARC, LR on
    size_boxes(gt, extent)). An input left None makes the attributes that
    need it all False (e.g. without poses VC and CM are never set);
    visibility None is taken as 1 where there is a
    box and in_view None as "always in view"."""
    gt, valid = _boxes(gt)
    n = len(gt)
    none = np.zeros(n, dtype=bool)
    vis = np.where(valid, 1.0, 0.0) if visibility is None else visibility
    sized = size_boxes(gt, extent)
    flags = {
        "SV": scale_variation(sized),
        "ARC": aspect_ratio_change(sized),
        "LR": low_resolution(sized),
        "FM": fast_motion(gt),
        "FOC": full_occlusion(gt, vis, in_view),
        "POC": partial_occlusion(gt, vis),
        "OV": out_of_view(gt, image_size, in_view),
        "BC": none if bc_similarity is None else background_clutter(gt, bc_similarity),
        "IV": illumination_variation(gt, np.full(n, np.nan) if luma is None else luma, conditions,
                                     change_every=change_every),
        "VC": none if camera_positions is None or target_positions is None or target_yaws is None
        else viewpoint_change(camera_positions, target_positions, target_yaws, valid),
        "CM": none if camera_quats is None else camera_motion(camera_quats, frame_hz),
        "SOB": none if sob_distance is None else similar_object(gt, sob_distance),
        "TA": target_absent(gt),
    }
    return {a: np.asarray(flags[a], dtype=bool).copy() for a in ABBREVS}


def per_sequence(flags):
    """{ABBREV: bool}: the attribute holds in at least SEQUENCE_MIN_FRACTION of
    the frames (0: in at least one frame)."""
    out = {}
    for a in ABBREVS:
        f = np.asarray(flags[a], dtype=bool)
        need = SEQUENCE_MIN_FRACTION[a]
        out[a] = bool(f.any()) if need <= 0 else bool(len(f) and f.mean() >= need)
    return out


# ----------------------------------------------------------------------------- files


def write_attribute_names(root):
    path = os.path.join(root, "attribute_names.txt")
    with open(path, "w", encoding="utf-8") as f:
        for abbrev, name in ATTRIBUTES:
            f.write("%s\t%s\n" % (abbrev, name))
    return path


def write_attributes(seq_dir, flags):
    """attributes.txt (one line of 0/1 flags, UAV123's form) and
    attributes_per_frame.csv (header of ABBREVs, one 0/1 row per frame)."""
    seq = per_sequence(flags)
    with open(os.path.join(seq_dir, "attributes.txt"), "w", encoding="utf-8") as f:
        f.write(",".join("1" if seq[a] else "0" for a in ABBREVS) + "\n")
    n = len(flags[ABBREVS[0]])
    table = np.stack([np.asarray(flags[a], dtype=int) for a in ABBREVS], axis=1) if n else np.zeros((0, len(ABBREVS)))
    with open(os.path.join(seq_dir, "attributes_per_frame.csv"), "w", encoding="utf-8") as f:
        f.write(",".join(ABBREVS) + "\n")
        for row in table:
            f.write(",".join(str(int(v)) for v in row) + "\n")
    return seq


def _read_csv(path):
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], [r for r in rows[1:] if r]
    return {name: np.array([float(r[i]) for r in body]) for i, name in enumerate(header)}


def attributes_of_sequence(seq_dir):
    """per_frame() of a sequence folder written by sim4cv.sequences, from its
    groundtruth_rect.txt, poses.csv, measures.csv and sequence.json alone."""
    import json
    with open(os.path.join(seq_dir, "sequence.json"), encoding="utf-8") as f:
        meta = json.load(f)
    gt = np.loadtxt(os.path.join(seq_dir, "groundtruth_rect.txt"), delimiter=",", ndmin=2)
    poses = _read_csv(os.path.join(seq_dir, "poses.csv"))
    measures = _read_csv(os.path.join(seq_dir, "measures.csv"))
    intr = meta["camera_intrinsics"]
    cam_p = np.stack([poses["cam_x"], poses["cam_y"], poses["cam_z"]], axis=1)
    cam_q = np.stack([poses["cam_qw"], poses["cam_qx"], poses["cam_qy"], poses["cam_qz"]], axis=1)
    tgt_p = np.stack([poses["target_x"], poses["target_y"], poses["target_z"]], axis=1)
    extent = np.stack([measures["proj_x"], measures["proj_y"], measures["proj_w"], measures["proj_h"]], axis=1)
    return per_frame(gt, (intr["width"], intr["height"]), visibility=poses["target_visibility"],
                     in_view=measures["in_view"] > 0, extent=extent, luma=measures["luma"],
                     bc_similarity=measures["bc_similarity"], sob_distance=measures["sob_distance"],
                     camera_positions=cam_p, camera_quats=cam_q, target_positions=tgt_p,
                     target_yaws=np.radians(poses["target_yaw_deg"]), frame_hz=meta.get("frame_hz", 30.0),
                     conditions=meta.get("conditions", {}).get("preset"),
                     change_every=int(meta.get("conditions", {}).get("randomize_every_frames", 0) or 0))
