"""The paper's augmentation study in one command (docs/driving.md,
"Augmentation comparison"): datasets without augmentation, with fixed views
and with random views, each trained and evaluated the same way.

    python3 -m sim4cv.driving compare --out DIR [--train-maps train] [--val-maps val] [--test-maps test]
        [--step 2.4] [--random-views 3] [--max-minutes 10] [--epochs 30] [--lr 2e-4] [--steer-waypoint 1] ...

Equal image budgets: "none" renders one image per lane pose, "random" 1 +
--random-views, "fixed" 1 + 24 (every offset x yaw of driving_labels'
fixed set); the fixed arm samples its poses proportionally further apart so
that it renders about as many images as the random arm (the paper gave its
fixed-view model more data and still found it worse). Everything else is
the same: maps, validation set, network, training budget, evaluation
(one controller, driving_control's options, for every arm: the paper's
rule by default).

Every arm's network takes the goal input (relabel sets it from the way the
route takes at each junction; the evaluation gives it as a navigation
system would): these maps' routes turn at junctions where the road also
goes on, which no image shows, so without it every arm fails at the same
junctions whatever its views (docs/driving.md, "Augmentation comparison").

Writes DIR/<arm>/{dataset,model,eval}/ and DIR/comparison.json,
DIR/comparison.md (the paper's table layout, with the paper's numbers).
Resumes: finished datasets, models (training.json finished) and
evaluations (driving.json) are reused.
"""

import json
import os
import sys
import time
from typing import List, Optional

from . import driving_control as dc
from . import driving_dataset as dd
from . import driving_eval as de
from . import driving_labels as dl
from . import driving_metrics as dm

ARMS = ("none", "fixed", "random")
ROWS = (("within_25cm", "%% in [-25 cm, 25 cm]"), ("within_50cm", "%% in [-50 cm, 50 cm]"),
        ("within_1m", "%% in [-1 m, 1 m]"), ("mean_deviation_cm", "Avg deviation [cm]"),
        ("lane_departures", "Lane departures"), ("completed", "Laps completed"))


def views_per_pose(arm: str, random_views: int) -> int:
    if arm == "none":
        return 1
    if arm == "random":
        return 1 + random_views
    return len(dl.FIXED_OFFSETS_M) * len(dl.FIXED_YAWS_DEG)  # (0, 0) is the original view


def run(out: str, train_maps: List[str], val_maps: List[str], test_maps: List[str], step: float = 2.4,
        random_views: int = 3, max_minutes: float = 10.0, epochs: int = 30, lr: float = 2e-4,
        surroundings=("desert", "urban"), arms=ARMS, max_samples: int = 0,
        controller: dc.Controller = dc.Controller(), log=print) -> dict:
    """Generates, trains and evaluates each arm (max_samples: lane poses per map at most, for tests)."""
    from . import driving_train as dt
    from .driving_relabel import relabel
    os.makedirs(out, exist_ok=True)
    val_dir = os.path.join(out, "val")
    dd.generate(val_maps, surroundings, val_dir, views="random", random_views=1, max_samples=max_samples, log=log)
    relabel(val_dir, log=log)  # every run: generate rebuilds labels.csv from its parts
    results, t0 = {}, time.monotonic()
    budget = views_per_pose("random", random_views)
    for arm in arms:
        base = os.path.join(out, arm)
        scale = max(views_per_pose(arm, random_views) / budget, 1.0) if arm == "fixed" else 1.0
        started = time.monotonic()
        meta = dd.generate(train_maps, surroundings, os.path.join(base, "dataset"), views=arm,
                           random_views=random_views, straight_step=step * scale, turn_step=step * scale / 4,
                           max_samples=max_samples, log=log)
        relabel(os.path.join(base, "dataset"), log=log)
        model_dir = os.path.join(base, "model")
        finished = False
        try:
            with open(os.path.join(model_dir, "training.json")) as f:
                finished = json.load(f).get("finished", False)
        except (OSError, ValueError):
            pass
        if not finished:
            dt.train(os.path.join(base, "dataset"), val_dir, model_dir, epochs=epochs, lr=lr, patience=3, goal=True,
                     max_minutes=max_minutes, threads=0, force=True, log=log)
        with open(os.path.join(model_dir, "training.json")) as f:
            training = json.load(f)
        eval_dir = os.path.join(base, "eval")
        if os.path.isfile(os.path.join(eval_dir, "driving.json")):
            with open(os.path.join(eval_dir, "driving.json")) as f:
                report = json.load(f)
        else:
            policy = de.NetworkPolicy(os.path.join(model_dir, "model.onnx"))
            policy.path = os.path.join(model_dir, "model.onnx")
            report = de.evaluate(policy, test_maps, surroundings, eval_dir, log=log, label=arm,
                                 controller=controller)
        results[arm] = {"images": meta["counts"]["images"], "samples": meta["counts"]["samples"],
                        "best_epoch": training["best_epoch"], "best_val_loss": training["best_val_loss"],
                        "epochs": len(training["epochs"]), "overall": report["overall"],
                        "seconds": round(time.monotonic() - started, 1)}
    comparison = {"settings": {"train_maps": train_maps, "val_maps": val_maps, "test_maps": test_maps,
                               "step_m": step, "random_views": random_views, "max_minutes": max_minutes,
                               "epochs": epochs, "lr": lr, **controller.settings()},
                  "arms": results, "paper": dm.PAPER, "seconds": round(time.monotonic() - t0, 1)}
    comparison["findings"] = findings(results)
    with open(os.path.join(out, "comparison.json"), "w") as f:
        json.dump(comparison, f, indent=1)
    with open(os.path.join(out, "comparison.md"), "w") as f:
        f.write(table(results))
    log(table(results))
    for line in comparison["findings"]:
        log(line)
    return comparison


def table(results: dict) -> str:
    """The paper's table layout: rows of metrics, a column per arm, then the paper's two columns."""
    arms = [a for a in ARMS if a in results]
    head = "| | " + " | ".join("%s views (here)" % a for a in arms) + " | random views (paper) | fixed views (paper) |"
    lines = [head, "|---" * (len(arms) + 3) + "|"]
    for key, label in ROWS:
        cells = [_cell(results[a]["overall"].get(key), key) for a in arms]
        paper = [_cell(dm.PAPER[p].get(key), key) for p in ("random", "fixed")]
        lines.append("| %s | %s |" % (label.replace("%%", "%"), " | ".join(cells + paper)))
    lines.append("| Training images | %s | | |" % " | ".join(str(results[a]["images"]) for a in arms))
    return "\n".join(lines) + "\n"


def _cell(value, key) -> str:
    if value is None:
        return "–"
    if key.startswith("within"):
        return "%.4f" % value
    if key == "mean_deviation_cm":
        return "%.2f" % value
    return str(value)


def findings(results: dict) -> List[str]:
    """Which of the paper's findings hold here, stated from the numbers."""
    out = []
    o = {a: r["overall"] for a, r in results.items()}
    if "none" in o:
        failed = o["none"]["runs"] - o["none"]["completed"]
        out.append("without augmentation: %d of %d laps left the road (paper: fails on every test track) -> %s"
                   % (failed, o["none"]["runs"], "holds" if failed == o["none"]["runs"] else
                      ("holds in part" if failed else "does not hold here")))
    if "random" in o and "fixed" in o and o["random"]["mean_deviation_cm"] is not None \
            and o["fixed"]["mean_deviation_cm"] is not None:
        better = o["random"]["mean_deviation_cm"] < o["fixed"]["mean_deviation_cm"]
        out.append("random views %.2f cm vs fixed views %.2f cm mean deviation (paper: random better, 7.12 vs "
                   "14.61 cm) -> %s" % (o["random"]["mean_deviation_cm"], o["fixed"]["mean_deviation_cm"],
                                        "holds" if better else "does not hold here"))
    return out


def main(argv: Optional[List[str]] = None) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving compare", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True)
    p.add_argument("--train-maps", nargs="+", default=["train"])
    p.add_argument("--val-maps", nargs="+", default=["val"])
    p.add_argument("--test-maps", nargs="+", default=["test"])
    p.add_argument("--surroundings", default="desert,urban")
    p.add_argument("--step", type=float, default=2.4, help="metres between lane poses on straights (turns: 1/4)")
    p.add_argument("--random-views", type=int, default=3)
    p.add_argument("--max-minutes", type=float, default=10.0, help="training time per arm")
    p.add_argument("--epochs", type=int, default=30)
    p.add_argument("--lr", type=float, default=2e-4)
    p.add_argument("--arms", default=",".join(ARMS))
    dc.add_arguments(p)
    a = p.parse_args(argv)
    controller = dc.from_arguments(p, a)
    from .driving_train import TrainError
    try:
        run(a.out, a.train_maps, a.val_maps, a.test_maps, a.step, a.random_views, a.max_minutes, a.epochs, a.lr,
            [s for s in a.surroundings.split(",") if s], [x for x in a.arms.split(",") if x],
            controller=controller, log=lambda m: print(m, flush=True))
    except (dd.DatasetError, de.EvalError, TrainError, RuntimeError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0
