"""The detectors of the realism probe (bench/realism_probe.py) and how their
boxes are matched to ground-truth walkers. All are OpenCV's own, trained on
real photographs, used with OpenCV's documented parameters and nothing tuned
for sim4cv's frames.

Matching: greedy one-to-one by IoU (highest first). A HOG window holds a
margin around the person, so, as OpenCV's samples/python/peopledetect.py
draws them, a HOG box is first shrunk by 15 % of its width on each side and
5 % of its height at top and bottom; a walker is found when such a box has
IoU >= 0.5 with the walker's tight ground-truth box ("body" rule). The raw
window's IoU >= 0.5 is reported too ("raw" rule). A Haar upper-body box
finds a walker when its centre lies in the upper half of the walker's box
and its height is 20-80 % of the walker's.
"""

import os
import re

import cv2
import numpy as np

IOU_MIN = 0.5
OPENCV_SHARE = "/usr/share/opencv4"  # Debian's opencv-data
HAAR_DIR = os.path.join(OPENCV_SHARE, "haarcascades")
# detectMultiScale as OpenCV's samples/python/peopledetect.py calls it.
HOG_PARAMS = {"winStride": (8, 8), "padding": (32, 32), "scale": 1.05}
HAAR_PARAMS = {"scaleFactor": 1.1, "minNeighbors": 3}


def _default_hog():
    hog = cv2.HOGDescriptor()  # 64x128 window (Dalal and Triggs, INRIA person data)
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return hog


def _daimler_hog():
    hog = cv2.HOGDescriptor((48, 96), (16, 16), (8, 8), (8, 8), 9)  # Daimler pedestrian benchmark window
    hog.setSVMDetector(cv2.HOGDescriptor_getDaimlerPeopleDetector())
    return hog


def hog_detectors():
    """name -> function(bgr image) -> list of (x, y, w, h) boxes."""
    detectors = {}
    for name, hog in (("hog_default", _default_hog()), ("hog_daimler", _daimler_hog())):
        def detect(bgr, hog=hog):
            boxes, _weights = hog.detectMultiScale(bgr, **HOG_PARAMS)
            return sorted(tuple(int(v) for v in box) for box in boxes)  # its threads return them in any order
        detectors[name] = detect
    return detectors


def haar_detectors(haar_dir=HAAR_DIR):
    """name -> function(bgr) -> boxes, for the full- and upper-body cascades
    found in haar_dir; {} and a reason when the folder lacks them."""
    detectors = {}
    for name, file in (("haar_fullbody", "haarcascade_fullbody.xml"), ("haar_upperbody", "haarcascade_upperbody.xml")):
        path = os.path.join(haar_dir, file)
        cascade = cv2.CascadeClassifier(path) if os.path.isfile(path) else None
        if cascade is None or cascade.empty():
            continue
        def detect(bgr, cascade=cascade):
            gray = cv2.equalizeHist(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY))
            return sorted(tuple(int(v) for v in box) for box in cascade.detectMultiScale(gray, **HAAR_PARAMS))
        detectors[name] = detect
    return detectors


def packaged_car_detectors(opencv_share=OPENCV_SHARE):
    """The packaged cascades (haarcascades/, lbpcascades/) whose name says
    car or vehicle. OpenCV 4.6's opencv-data ships none: faces, eyes, cat
    faces, smiles, bodies and number plates only."""
    names = []
    for folder in ("haarcascades", "lbpcascades"):
        path = os.path.join(opencv_share, folder)
        if os.path.isdir(path):
            names += [f for f in sorted(os.listdir(path)) if re.search(r"(^|_)(car|cars|vehicle)(_|\.|$)", f)]
    return names


def iou(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    w = min(ax + aw, bx + bw) - max(ax, bx)
    h = min(ay + ah, by + bh) - max(ay, by)
    if w <= 0 or h <= 0:
        return 0.0
    inter = w * h
    return inter / float(aw * ah + bw * bh - inter)


def body_of(box):
    """A HOG window shrunk to the person inside it (peopledetect.py's padding)."""
    x, y, w, h = box
    pad_w, pad_h = int(0.15 * w), int(0.05 * h)
    return (x + pad_w, y + pad_h, w - 2 * pad_w, h - 2 * pad_h)


def upper_body_hit(detection, walker):
    x, y, w, h = detection
    wx, wy, ww, wh = walker
    cx, cy = x + w / 2.0, y + h / 2.0
    return wx <= cx <= wx + ww and wy <= cy <= wy + wh / 2.0 and 0.2 * wh <= h <= 0.8 * wh


def match(detections, walkers, rule):
    """Greedy one-to-one matching; returns (found walker indices, unmatched detection count).
    rule: "body" (shrunk HOG box, IoU), "raw" (the box as given, IoU) or "upper" (upper_body_hit)."""
    pairs = []
    for d, det in enumerate(detections):
        for w, walker in enumerate(walkers):
            if rule == "upper":
                score = 1.0 if upper_body_hit(det, walker) else 0.0
            else:
                score = iou(body_of(det) if rule == "body" else det, walker)
                score = score if score >= IOU_MIN else 0.0
            if score > 0.0:
                pairs.append((-score, d, w))
    used_d, found = set(), set()
    for _score, d, w in sorted(pairs):
        if d not in used_d and w not in found:
            used_d.add(d)
            found.add(w)
    return sorted(found), len(detections) - len(used_d)


def _read_images(path, video_frames):
    """(label, bgr) of a photograph, or of every 100th frame of a video (the first video_frames)."""
    if not path.endswith((".avi", ".mp4")):
        bgr = cv2.imread(path, cv2.IMREAD_COLOR)
        return [(os.path.basename(path), bgr)] if bgr is not None else []
    video, images = cv2.VideoCapture(path), []
    for index in range(0, 100 * video_frames, 100):
        video.set(cv2.CAP_PROP_POS_FRAMES, index)
        ok, bgr = video.read()
        if ok:
            images.append(("%s#%d" % (os.path.basename(path), index), bgr))
    return images


def probe_photo(path, detectors, video_frames=8):
    """Each detector's boxes on real photographs or video frames (no ground truth: none that
    Debian packages is annotated)."""
    results = []
    for label, bgr in _read_images(path, video_frames):
        result = {"photo": label, "width": int(bgr.shape[1]), "height": int(bgr.shape[0])}
        for name, detect in detectors.items():
            result[name] = [list(box) for box in detect(bgr)]
        results.append(result)
    return results or [{"photo": os.path.basename(path), "error": "cannot read"}]


def mask_box(mask, object_id):
    """The tight box and pixel count of object_id in a mask: ((x, y, w, h), n), or (None, 0)."""
    ys, xs = np.nonzero(mask == object_id)
    if len(xs) == 0:
        return None, 0
    return (int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)), len(xs)
