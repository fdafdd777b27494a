"""The model card of a driving model (docs/driving.md, "Model card"):
`model.json` beside `model.onnx` / `model.pt`, saying what the network takes
(input size, channel order, value range, normalisation, the goal input),
what it gives, and the controller settings it was selected with, with the
numbers it was selected on. `evaluate` and `drive` (and the C++ client
`sim4cv_drive`) take their controller settings from it, so the plain

    python3 -m sim4cv.driving evaluate --model models/driving/model.onnx --maps test --out DIR

drives as the model was chosen to drive; a command-line flag still wins,
and the report says where each setting came from. `train` and `head` write
a card (the paper's controller, not yet selected in closed loop).
"""

import json
import os
from typing import Dict, Optional, Tuple

CARD_NAME = "model.json"
FORMAT = "sim4cv driving model card 1"
OUTPUTS = ["v1", "h1", "v2", "h2", "v3", "h3", "v4", "h4"]

# The settings a card's "controller" holds: card key -> (command-line dest,
# flag, built-in default, check). The defaults are the paper's rule at 8 m/s, 30 Hz;
# a default of None (no bend limit) is left out of a new card.
SETTINGS = {
    "steer_waypoint": ("steer_waypoint", "--steer-waypoint", 1, lambda v: 1 <= v <= 4),
    "steer_gain": ("steer_gain", "--steer-gain", 1.0, lambda v: v > 0),
    "turn_slowdown": ("turn_slowdown", "--turn-slowdown", 0.0, lambda v: v >= 0),
    "bend_correction": ("bend_correction", "--bend-correction", 0.0, lambda v: 0 <= v <= 1),
    "bend_limit_m": ("bend_limit", "--bend-limit", None, lambda v: v > 0),
    "speed_m_s": ("speed", "--speed", 8.0, lambda v: v > 0),
    "frame_hz": ("frame_hz", "--frame-hz", 30.0, lambda v: v > 0),
}


class CardError(RuntimeError):
    """A model card that cannot be used; the message names the file and the field."""


def card_path(model_path: str) -> str:
    """model.json in the model file's folder."""
    return os.path.join(os.path.dirname(os.path.abspath(model_path)), CARD_NAME)


def read(model_path: str) -> Optional[dict]:
    """The card beside `model_path`, checked; None if the folder has none."""
    path = card_path(model_path)
    if not os.path.isfile(path):
        return None
    try:
        with open(path) as f:
            card = json.load(f)
    except (OSError, ValueError) as e:
        raise CardError("model card %s is not readable JSON: %s" % (path, e)) from None
    if not isinstance(card, dict) or card.get("format") != FORMAT:
        raise CardError("model card %s: expected \"format\": \"%s\"" % (path, FORMAT))
    for section in ("input", "controller"):
        if not isinstance(card.get(section), dict):
            raise CardError("model card %s has no \"%s\" object" % (path, section))
    for key in ("height", "width", "goal"):
        if key not in card["input"]:
            raise CardError("model card %s: input has no \"%s\"" % (path, key))
    for key, value in card["controller"].items():
        if key not in SETTINGS:
            raise CardError("model card %s: unknown controller setting \"%s\" (known: %s)"
                            % (path, key, ", ".join(SETTINGS)))
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not SETTINGS[key][3](value):
            raise CardError("model card %s: controller setting \"%s\" has a bad value %r" % (path, key, value))
    card["path"] = path
    return card


def check_model(card: dict, height: int, width: int, use_goal: bool, model_path: str) -> None:
    """Refuses a card that describes another network than the file beside it."""
    i = card["input"]
    if (i["height"], i["width"], bool(i["goal"])) != (height, width, bool(use_goal)):
        raise CardError("model card %s describes a %dx%d network%s, but %s is %dx%d%s"
                        % (card["path"], i["width"], i["height"], " with a goal input" if i["goal"] else "",
                           model_path, width, height, " with a goal input" if use_goal else ""))


def apply(args, card: Optional[dict]) -> Dict[str, str]:
    """Fills the options the command line left unset (None) from the card,
    else from the built-in defaults; returns {setting: where it came from}
    for the settings `args` has."""
    sources = {}
    for key, (dest, flag, default, _) in SETTINGS.items():
        if not hasattr(args, dest):
            continue
        if getattr(args, dest) is not None:
            sources[key] = flag
        elif card is not None and key in card["controller"]:
            value = card["controller"][key]
            whole = isinstance(default, int) and value == int(value)
            setattr(args, dest, int(value) if whole else float(value))
            sources[key] = "model card %s" % card["path"]
        else:
            setattr(args, dest, default)
            sources[key] = "default"
    return sources


def describe(args, sources: Dict[str, str]) -> str:
    """One line for the log: each setting, its value and its source."""
    return "settings: " + ", ".join("%s %s (%s)" % (key, getattr(args, SETTINGS[key][0]), source)
                                    for key, source in sources.items())


def card_for(height: int, width: int, use_goal: bool, controller: Optional[dict] = None,
             selected: Optional[dict] = None, input_norm: str = "fixed") -> dict:
    """A card's content: the network's contract (docs/driving.md, "ONNX
    contract") and the controller (default: the paper's rule, not selected)."""
    from .driving_dataset import CAMERA_SETTINGS
    from .driving_net import NORMALISATIONS
    return {
        "format": FORMAT,
        "files": {"onnx": "model.onnx", "torch": "model.pt", "training": "training.json"},
        "input": {"height": height, "width": width, "channels": "RGB", "layout": "NCHW", "dtype": "float32",
                  "value_range": [0, 255], "normalisation": NORMALISATIONS[input_norm],
                  "resize": "cv2.INTER_AREA from the camera's image", "goal": bool(use_goal),
                  "camera": dict(CAMERA_SETTINGS)},
        "output": {"names": OUTPUTS, "unit": "m", "axes": "v forward, h positive to the right",
                   "spacing_m": 2.0},
        "controller": controller or {key: s[2] for key, s in SETTINGS.items() if s[2] is not None},
        "selected": selected or {"status": "not selected in closed loop: the paper's controller"},
    }


def write(folder: str, height: int, width: int, use_goal: bool, input_norm: str = "fixed") -> str:
    """Writes folder/model.json for a freshly trained network; returns its path."""
    path = os.path.join(folder, CARD_NAME)
    with open(path, "w") as f:
        json.dump(card_for(height, width, use_goal, input_norm=input_norm), f, indent=2)
        f.write("\n")
    return path


def for_model(model_path: Optional[str], height_width_goal: Optional[Tuple[int, int, bool]]) -> Optional[dict]:
    """read() and check_model() for a loaded policy's file (None: no model, no card)."""
    if not model_path:
        return None
    card = read(model_path)
    if card is not None and height_width_goal is not None:
        check_model(card, *height_width_goal, model_path)
    return card
