"""Averages the weights of several models of one training run (docs/driving.md,
"Averaging epochs"): stochastic weight averaging over the epochs `train
--keep-epochs` wrote, which gives one model of the same size and speed that is
usually steadier in closed loop than any single epoch:

    python3 -m sim4cv.driving average --models OUT/epochs/03.pt OUT/epochs/04.pt ... --out DIR

The models must share the architecture (input size, goal input); WaypointNet
has no batch normalisation, so the plain mean of the weights is the whole
method. Writes DIR/model.pt, DIR/model.onnx and DIR/average.json (the sources).
"""

import json
import os
import pickle
import sys
from typing import List, Optional, Sequence


class AverageError(RuntimeError):
    pass


def average(paths: Sequence[str], out: str, log=print) -> dict:
    from .driving_net import export_onnx
    from . import driving_card
    from .driving_train import _save, load_model
    from .driving_weights import load_saved
    if len(paths) < 2:
        raise AverageError("average needs at least 2 models, got %d" % len(paths))
    saved = []
    for p in paths:
        try:
            saved.append(load_saved(p))
        except (OSError, RuntimeError, EOFError, ValueError, pickle.UnpicklingError) as e:
            raise AverageError("%s: not a model.pt (%s)" % (p, e))
        if not isinstance(saved[-1], dict) or "state_dict" not in saved[-1] or "settings" not in saved[-1]:
            raise AverageError("%s: not a model.pt of sim4cv.driving_train (no state_dict and settings)" % p)
    first, shape = saved[0], _shape(saved[0])
    for p, s in zip(paths[1:], saved[1:]):
        if _shape(s) != shape:
            raise AverageError("%s has %s, %s has %s: only models of one architecture average"
                               % (paths[0], _describe(shape), p, _describe(_shape(s))))
    state = {k: sum(s["state_dict"][k] for s in saved) / len(saved) for k in first["state_dict"]}
    os.makedirs(out, exist_ok=True)
    settings = dict(first["settings"], averaged=[os.path.abspath(p) for p in paths])
    _save(os.path.join(out, "model.pt"), state, settings, 0)
    model = load_model(os.path.join(out, "model.pt"))
    export_onnx(model, os.path.join(out, "model.onnx"), model.height, model.width)
    driving_card.write(out, model.height, model.width, model.use_goal, model.input_norm)  # a new network: not selected yet
    meta = dict(models=settings["averaged"], height=model.height, width=model.width, goal=model.use_goal,
                outputs=["model.pt", "model.onnx", "model.json", "average.json"])
    with open(os.path.join(out, "average.json"), "w") as f:
        json.dump(meta, f, indent=2)
    log("averaged %d models into %s" % (len(paths), out))
    return meta


def _shape(saved: dict):
    s = saved["settings"]
    return (s.get("height"), s.get("width"), bool(s.get("goal")),
            tuple((k, tuple(v.shape)) for k, v in saved["state_dict"].items()))


def _describe(shape) -> str:
    return "%sx%s goal=%s" % shape[:3]


def main(argv: Optional[List[str]] = None) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving average", description=__doc__.split("\n\n")[0])
    p.add_argument("--models", required=True, nargs="+", help="model.pt files of one architecture")
    p.add_argument("--out", required=True, help="folder for model.pt, model.onnx, average.json")
    a = p.parse_args(argv)
    try:
        average(a.models, a.out)
    except AverageError as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0
