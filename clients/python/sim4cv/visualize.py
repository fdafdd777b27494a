"""Colour images of the ground-truth channels, for looking at and saving
(numpy only; pair with any PNG writer, e.g. cv2.imwrite on the RGB reversed).

    semantic_colours(image_array(frame, "semantic"))   # (h, w, 3) uint8, Cityscapes palette
    normals_colours(image_array(frame, "normals"))
    flow_colours(image_array(frame, "flow"))           # the usual colour wheel
    depth_colours(image_array(frame, "depth"))
"""

import numpy as np

# id -> (name, RGB colour, Cityscapes trainId it folds into; 255 = ignore).
# The table of docs/protocol.md, "Semantic classes" (protocol/semantic_classes.h).
SEMANTIC_CLASSES = {
    0: ("road", (128, 64, 128), 0),
    1: ("sidewalk", (244, 35, 232), 1),
    2: ("building", (70, 70, 70), 2),
    3: ("wall", (102, 102, 156), 3),
    4: ("fence", (190, 153, 153), 4),
    5: ("pole", (153, 153, 153), 5),
    6: ("traffic light", (250, 170, 30), 6),
    7: ("traffic sign", (220, 220, 0), 7),
    8: ("vegetation", (107, 142, 35), 8),
    9: ("terrain", (152, 251, 152), 9),
    10: ("sky", (70, 130, 180), 10),
    11: ("person", (220, 20, 60), 11),
    12: ("rider", (255, 0, 0), 12),
    13: ("car", (0, 0, 142), 13),
    14: ("truck", (0, 0, 70), 14),
    15: ("bus", (0, 60, 100), 15),
    16: ("train", (0, 80, 100), 16),
    17: ("motorcycle", (0, 0, 230), 17),
    18: ("bicycle", (119, 11, 32), 18),
    19: ("lane marking", (255, 255, 255), 0),
    20: ("crosswalk", (200, 200, 200), 0),
    21: ("uav", (255, 128, 0), 255),
    22: ("obstacle", (180, 100, 40), 4),
    255: ("unlabelled", (0, 0, 0), 255),
}

_PALETTE = np.zeros((256, 3), np.uint8)
_FOLD = np.full(256, 255, np.uint8)
for _id, (_name, _colour, _fold) in SEMANTIC_CLASSES.items():
    _PALETTE[_id] = _colour
    _FOLD[_id] = _fold


def semantic_colours(ids):
    """(h, w) class ids -> (h, w, 3) uint8 RGB in the Cityscapes palette."""
    return _PALETTE[np.asarray(ids, np.uint8)]


def cityscapes_train_ids(ids):
    """(h, w) sim4cv class ids -> Cityscapes trainIds (255 = ignore), for
    evaluating a network trained on Cityscapes without remapping by hand."""
    return _FOLD[np.asarray(ids, np.uint8)]


def normals_colours(normals):
    """(h, w, 3) unit normals (OpenCV camera axes) -> RGB: (n + 1) / 2; sky black."""
    n = np.asarray(normals, np.float32)
    rgb = ((n + 1.0) * 127.5).clip(0, 255).astype(np.uint8)
    rgb[np.all(n == 0, axis=-1)] = 0
    return rgb


def flow_colours(flow, max_magnitude=None):
    """(h, w, 2) flow in pixels -> RGB on the colour wheel: hue is the
    direction, saturation the magnitude relative to `max_magnitude` (default:
    the largest finite magnitude in the image). NaN (no previous pixel) is black."""
    f = np.asarray(flow, np.float32)
    dx, dy = f[..., 0], f[..., 1]
    valid = np.isfinite(dx) & np.isfinite(dy)
    magnitude = np.where(valid, np.hypot(dx, dy), 0.0)
    if max_magnitude is None:
        max_magnitude = float(magnitude.max()) if magnitude.size else 0.0
    saturation = np.clip(magnitude / max(max_magnitude, 1e-6), 0.0, 1.0)
    hue = (np.arctan2(-np.where(valid, dy, 0), -np.where(valid, dx, 0)) / np.pi + 1.0) * 3.0  # [0, 6)
    sector = np.floor(hue).astype(np.int32) % 6
    frac = hue - np.floor(hue)
    one = np.ones_like(frac)
    # HSV with value 1: the standard hue wheel, whitened towards zero motion.
    table = [(one, frac, 0 * one), (1 - frac, one, 0 * one), (0 * one, one, frac),
             (0 * one, 1 - frac, one), (frac, 0 * one, one), (one, 0 * one, 1 - frac)]
    rgb = np.zeros(f.shape[:-1] + (3,), np.float32)
    for k, (r, g, b) in enumerate(table):
        pick = sector == k
        rgb[pick] = np.stack([r[pick], g[pick], b[pick]], axis=-1)
    rgb = 1.0 - saturation[..., None] * (1.0 - rgb)
    out = (rgb * 255.0).astype(np.uint8)
    out[~valid] = 0
    return out


def depth_colours(depth, far=None):
    """(h, w) depth in metres -> RGB grey levels, near bright; sky black."""
    d = np.asarray(depth, np.float32)
    finite = np.isfinite(d)
    if far is None:
        far = float(d[finite].max()) if finite.any() else 1.0
    level = np.where(finite, 1.0 - np.clip(d / max(far, 1e-6), 0.0, 1.0), 0.0)
    return np.repeat((level * 255).astype(np.uint8)[..., None], 3, axis=-1)
