"""Trains the driving case study's WaypointNet (docs/driving.md, "Training")
on datasets written by sim4cv.driving_dataset.

    python3 -m sim4cv.driving_train --train DIR --val DIR --out OUT \\
        [--epochs N] [--batch 32] [--lr 5e-5] [--patience 5] [--downscale 2] \\
        [--goal] [--max-samples N] [--threads N] [--max-minutes M] [--force]
        [--init MODEL.pt] [--junction-weight K] [--obstacle-weight K] [--keep-epochs]
        [--input-norm fixed|image] [--augment STRENGTH]

L2 (MSE) loss on the 8 offsets v1 h1 ... v4 h4, Adam, the validation loss
after every epoch, early stopping on it (the best state is kept). Writes
OUT/model.pt (state dict + settings), OUT/model.onnx (export_onnx),
OUT/model.json (the model card: sim4cv.driving_card) and
OUT/training.json (per-epoch losses, samples/s, seconds, settings, best epoch).

Refusals (exit status 2, "error: ..."): a dataset folder without labels.csv,
labels.csv missing columns, an OUT holding a model trained with other
settings (unless --force).
"""

import argparse
import copy
import csv
import json
import math
import os
import sys
import time
from typing import Dict, List, Optional

import numpy as np
import torch
from torch.utils.data import ConcatDataset, DataLoader, Dataset, WeightedRandomSampler

from sim4cv import driving_card
from sim4cv.driving_augment import condition_augment
from sim4cv.driving_weights import load_saved
from sim4cv.driving_net import DEFAULT_HEIGHT, DEFAULT_WIDTH, NORMALISATIONS, WaypointNet, export_onnx

TARGETS = ["v1", "h1", "v2", "h2", "v3", "h3", "v4", "h4"]
REQUIRED = ["image"] + TARGETS + ["goal"]
# the settings that make two models different (a rerun with other ones is refused unless --force)
MODEL_SETTINGS = ("train", "val", "epochs", "batch", "lr", "patience", "downscale", "goal", "max_samples",
                  "junction_weight", "obstacle_weight", "input_norm", "augment")
# relabel's 0/1 columns that --junction-weight and --obstacle-weight oversample
WEIGHTED = ("junction", "obstacle")


class TrainError(Exception):
    """A refusal: the message names the problem."""


def read_labels(folder: str, max_samples: int = 0) -> List[Dict[str, str]]:
    path = os.path.join(folder, "labels.csv")
    if not os.path.isdir(folder):
        raise TrainError("dataset folder %s does not exist" % folder)
    if not os.path.isfile(path):
        raise TrainError("dataset folder %s has no labels.csv" % folder)
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in REQUIRED if c not in (reader.fieldnames or [])]
        if missing:
            raise TrainError("%s is missing columns: %s" % (path, ", ".join(missing)))
        rows = list(reader)
    if not rows:
        raise TrainError("%s has no rows" % path)
    if max_samples and max_samples > 0:
        rows = rows[:max_samples]
    return rows


class DrivingDataset(Dataset):
    """labels.csv rows -> (image float32 3xHxW in 0..255 RGB, goal float32 (1,), targets float32 (8,))."""

    def __init__(self, folder: str, downscale: int = 1, max_samples: int = 0):
        import cv2  # noqa: F401  (fail early without OpenCV)
        self.folder = folder
        self.downscale = downscale
        self.rows = read_labels(folder, max_samples)
        self.targets = np.array([[float(r[c]) for c in TARGETS] for r in self.rows], dtype=np.float32)
        self.goals = np.array([float(r["goal"] or 0) for r in self.rows], dtype=np.float32).reshape(-1, 1)
        # relabel's columns, e.g. junction: the pose is at a junction of its route (None: not relabelled)
        self.flags = {c: (np.array([r[c] == "1" for r in self.rows]) if c in self.rows[0] else None)
                      for c in WEIGHTED}
        if not np.all(np.isfinite(self.targets)):
            raise TrainError("%s: labels.csv holds non-finite targets" % folder)
        self.height = DEFAULT_HEIGHT // downscale
        self.width = DEFAULT_WIDTH // downscale
        # decoded images, kept after the first epoch: PNG decoding and the
        # resize cost about as much as a training step (90x160: 43 KB each).
        # One array, not one per image: small arrays kept between the decoder's
        # large transient ones fragmented the heap to 7 times their size (a
        # 68,000-image run grew to 24 GB). np.zeros commits pages as they fill.
        self.cache = np.zeros((len(self.rows), 3, self.height, self.width), dtype=np.uint8)
        self.cached = np.zeros(len(self.rows), dtype=bool)

    def __len__(self):
        return len(self.rows)

    def __getitem__(self, i):
        if not self.cached[i]:
            self.cache[i] = self._read(i)
            self.cached[i] = True
        image = torch.from_numpy(self.cache[i]).float()
        return image, torch.from_numpy(self.goals[i]), torch.from_numpy(self.targets[i])

    def _read(self, i: int) -> np.ndarray:
        """The image of row i as uint8 3 x H x W RGB."""
        import cv2
        path = os.path.join(self.folder, self.rows[i]["image"])
        img = cv2.imread(path, cv2.IMREAD_COLOR)
        if img is None:
            raise TrainError("cannot read image %s" % path)
        img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        if img.shape[:2] != (self.height, self.width):
            img = cv2.resize(img, (self.width, self.height), interpolation=cv2.INTER_AREA)
        return np.ascontiguousarray(img.transpose(2, 0, 1))


def _evaluate(model, loader, use_goal):
    model.eval()
    total, n = 0.0, 0
    with torch.no_grad():
        for image, goal, target in loader:
            out = model(image, goal) if use_goal else model(image)
            total += float(torch.nn.functional.mse_loss(out, target, reduction="sum")) / target.shape[1]
            n += target.shape[0]
    return total / max(n, 1)


def _order(parts, folders, weights: Dict[str, float], gen) -> dict:
    """DataLoader arguments: a shuffle, or, with a weight K > 1 for a column
    of WEIGHTED (e.g. junction), a draw in which each sample flagged there is
    K times as likely as another (weights of several columns multiply; as
    many draws as samples: an epoch stays one dataset's worth)."""
    used = {c: k for c, k in weights.items() if k != 1.0}
    if not used:
        return dict(shuffle=True)
    draw = np.ones(sum(len(part) for part in parts))
    for column, k in used.items():
        missing = [f for f, part in zip(folders, parts) if part.flags[column] is None]
        if missing:
            raise TrainError("--%s-weight needs the %s column of `relabel`; %s has none (run "
                             "python3 -m sim4cv.driving relabel --dataset %s)"
                             % (column, column, ", ".join(missing), " ".join(missing)))
        draw *= np.where(np.concatenate([part.flags[column] for part in parts]), k, 1.0)
    return dict(sampler=WeightedRandomSampler(torch.from_numpy(draw), len(draw), replacement=True, generator=gen))


def check_run(epochs: int, batch: int, lr: float, weights: Dict[str, float]) -> None:
    """The refusals of a run's numbers: epochs, batch, learning rate, and each
    oversampling weight (`weights`: column -> K, e.g. junction -> 3)."""
    if epochs < 1 or batch < 1 or not lr > 0:
        raise TrainError("--epochs and --batch must be >= 1 and --lr > 0")
    for column, k in weights.items():
        if not k >= 1.0:
            raise TrainError("--%s-weight must be >= 1, got %g" % (column.replace("_", "-"), k))


def record_weights(settings: dict, weights: Dict[str, float]) -> None:
    """The weights into `settings` as COLUMN_weight, only those in use (K != 1),
    so older models' settings still match; an inherited entry is replaced."""
    for column, k in weights.items():
        settings.pop(column + "_weight", None)
        if k != 1.0:
            settings[column + "_weight"] = k


def _check_out(out: str, settings: dict, force: bool, keys=MODEL_SETTINGS) -> None:
    path = os.path.join(out, "training.json")
    if os.path.exists(out) and not os.path.isdir(out):
        raise TrainError("output %s is not a folder" % out)
    if force or not os.path.isfile(path):
        if not force and os.path.isfile(os.path.join(out, "model.pt")):
            raise TrainError("%s holds model.pt but no training.json (use --force to overwrite)" % out)
        return
    try:
        with open(path) as f:
            old = json.load(f).get("settings", {})
    except (OSError, ValueError) as e:
        raise TrainError("%s: unreadable training.json (%s); use --force to overwrite" % (out, e))
    differ = [k for k in keys if old.get(k) != settings.get(k)]
    if differ:
        raise TrainError("%s holds a model trained with other settings (%s); use --force to overwrite"
                         % (out, ", ".join("%s: %r -> %r" % (k, old.get(k), settings.get(k)) for k in differ)))


def train(train_dir, val_dir: str, out: str, epochs: int = 50, batch: int = 32, lr: float = 5e-5,
          patience: int = 5, downscale: int = 2, goal: bool = False, max_samples: int = 0,
          threads: int = 0, force: bool = False, seed: int = 0, max_minutes: float = 0.0, init: str = "",
          junction_weight: float = 1.0, obstacle_weight: float = 1.0, keep_epochs: bool = False,
          input_norm: str = "fixed", augment: float = 0.0, log=print) -> dict:
    if downscale not in (1, 2):
        raise TrainError("--downscale must be 1 (180x320) or 2 (90x160), got %d" % downscale)
    weights = {"junction": junction_weight, "obstacle": obstacle_weight}
    check_run(epochs, batch, lr, weights)
    train_dirs = [train_dir] if isinstance(train_dir, str) else list(train_dir)
    train_path = (os.path.abspath(train_dirs[0]) if len(train_dirs) == 1
                  else [os.path.abspath(d) for d in train_dirs])
    settings = dict(train=train_path, val=os.path.abspath(val_dir), epochs=epochs, batch=batch,
                    lr=lr, patience=patience, downscale=downscale, goal=goal, max_samples=max_samples,
                    threads=threads, seed=seed)
    record_weights(settings, weights)
    # recorded only when not the default, so older models' settings still match
    if input_norm != "fixed":
        settings["input_norm"] = input_norm
    if augment > 0:
        settings["augment"] = augment
    if input_norm not in NORMALISATIONS:
        raise TrainError("--input-norm %s: one of %s" % (input_norm, ", ".join(NORMALISATIONS)))
    parts = [DrivingDataset(d, downscale, max_samples) for d in train_dirs]
    train_set = parts[0] if len(parts) == 1 else ConcatDataset(parts)
    train_set.height, train_set.width = parts[0].height, parts[0].width
    val_set = DrivingDataset(val_dir, downscale, max_samples)
    _check_out(out, settings, force)
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        raise TrainError("cannot create output folder %s: %s" % (out, e))
    if threads and threads > 0:
        torch.set_num_threads(threads)
    torch.manual_seed(seed)
    height, width = train_set.height, train_set.width
    settings.update(height=height, width=width, train_samples=len(train_set), val_samples=len(val_set))
    model = WaypointNet(height, width, use_goal=goal, input_norm=input_norm)
    if init:  # go on from a trained model (e.g. one whose time budget ran out)
        try:
            start = load_model(init)
        except (OSError, KeyError, RuntimeError) as e:
            raise TrainError("--init %s: not a model.pt of this trainer (%s)" % (init, e))
        if ((start.height, start.width) != (height, width) or (start.use_goal and not goal)
                or (start.input_norm == "image" and input_norm != "image")):
            raise TrainError("--init %s was trained at %dx%d goal=%s input norm %s, not %dx%d goal=%s input norm %s" % (
                init, start.height, start.width, start.use_goal, start.input_norm, height, width, goal, input_norm))
        state = start.state_dict()
        if goal and not start.use_goal:  # the goal's weights into fc1 start at 0: the old model's outputs
            state["fc1.weight"] = torch.cat([state["fc1.weight"], torch.zeros(state["fc1.weight"].shape[0], 1)], 1)
        if input_norm != start.input_norm:  # "fixed" -> "image": the new normalisation keeps its starting scale
            state.update({k: v for k, v in model.state_dict().items() if k.startswith("norm.")})
        model.load_state_dict(state)
        settings["init"] = os.path.abspath(init)
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    gen = torch.Generator()
    gen.manual_seed(seed)
    train_loader = DataLoader(train_set, batch_size=batch, generator=gen,
                              **_order(parts, train_dirs, weights, gen))
    val_loader = DataLoader(val_set, batch_size=batch, shuffle=False)

    history, best, best_epoch, best_state, waited = [], math.inf, 0, None, 0
    log("training on %d samples (%s), validating on %d, %dx%d, %d epochs at most"
        % (len(train_set), ", ".join(train_dirs), len(val_set), height, width, epochs))
    for epoch in range(1, epochs + 1):
        t0 = time.time()
        model.train()
        total, n = 0.0, 0
        for image, g, target in train_loader:
            image = condition_augment(image, augment)  # the batch itself when augment is 0
            opt.zero_grad()
            outp = model(image, g) if goal else model(image)
            loss = torch.nn.functional.mse_loss(outp, target)
            loss.backward()
            opt.step()
            total += float(loss) * target.shape[0]
            n += target.shape[0]
        train_seconds = time.time() - t0
        train_loss = total / max(n, 1)
        val_loss = _evaluate(model, val_loader, goal)
        seconds = time.time() - t0
        entry = dict(epoch=epoch, train_loss=train_loss, val_loss=val_loss, seconds=seconds,
                     train_samples_per_s=n / train_seconds if train_seconds > 0 else None)
        history.append(entry)
        if keep_epochs:  # every epoch's weights, for choosing by closed loop or averaging (driving_average)
            _save(os.path.join(out, "epochs", "%02d.pt" % epoch), model.state_dict(), settings, epoch)
        improved = val_loss < best
        if improved:
            best, best_epoch, best_state, waited = val_loss, epoch, copy.deepcopy(model.state_dict()), 0
            _write(out, model, best_state, settings, history, best_epoch, best, epochs, finished=False)
        else:
            waited += 1
        log("epoch %d/%d: train %.5f  val %.5f%s  %.1f s  %.1f samples/s"
            % (epoch, epochs, train_loss, val_loss, " (best)" if improved else "", seconds,
               entry["train_samples_per_s"] or 0.0))
        if max_minutes > 0 and sum(e["seconds"] for e in history) > 60.0 * max_minutes:
            log("time budget of %g minutes spent after epoch %d (best: epoch %d, %.5f)"
                % (max_minutes, epoch, best_epoch, best))
            break
        if patience > 0 and waited >= patience:
            log("early stop: no better validation loss for %d epochs (best: epoch %d, %.5f)"
                % (patience, best_epoch, best))
            break
    if best_state is None:  # every val loss was NaN: keep the last state
        best_state, best_epoch = copy.deepcopy(model.state_dict()), len(history)
    meta = _write(out, model, best_state, settings, history, best_epoch, best, epochs, finished=True)
    log("best epoch %d (val %.5f); wrote %s" % (best_epoch, best, out))
    return meta


def _write(out, model, best_state, settings, history, best_epoch, best, epochs, finished) -> dict:
    """model.pt, model.onnx and training.json of the best state so far: written
    after every better epoch too, so an interrupted training leaves a model."""
    snapshot = copy.deepcopy(model)
    snapshot.load_state_dict(best_state)
    snapshot.eval()
    _save(os.path.join(out, "model.pt"), best_state, settings, best_epoch)
    export_onnx(snapshot, os.path.join(out, "model.onnx"), settings["height"], settings["width"])
    # a new network: its card has the paper's controller until one is chosen in closed loop
    driving_card.write(out, settings["height"], settings["width"], settings["goal"], settings.get("input_norm", "fixed"))
    meta = dict(settings=settings, epochs=history, best_epoch=best_epoch, best_val_loss=best, finished=finished,
                stopped_early=finished and len(history) < epochs,
                samples_per_s=(sum(e["train_samples_per_s"] or 0 for e in history) / len(history)),
                outputs=["model.pt", "model.onnx", "model.json", "training.json"])
    with open(os.path.join(out, "training.json"), "w") as f:
        json.dump(meta, f, indent=2)
    return meta


def _save(path: str, state, settings: dict, epoch: int) -> None:
    """A model.pt: the weights with the settings load_model needs."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    torch.save(dict(state_dict=state, settings=settings, best_epoch=epoch, targets=TARGETS), path)


def load_model(path: str) -> WaypointNet:
    """Loads OUT/model.pt back into a WaypointNet (eval mode)."""
    return model_from(load_saved(path))


def model_from(saved: dict) -> WaypointNet:
    """The WaypointNet (eval mode) of a loaded model.pt's contents."""
    s = saved["settings"]
    model = WaypointNet(s["height"], s["width"], use_goal=s["goal"], input_norm=s.get("input_norm", "fixed"))
    model.load_state_dict(saved["state_dict"])
    return model.eval()


def add_shared_arguments(p: argparse.ArgumentParser) -> None:
    """The options `train` and `head` share: the data, the output, the oversampling, the run."""
    p.add_argument("--train", required=True, nargs="+", help="training dataset folder(s) (each holds labels.csv)")
    p.add_argument("--val", required=True, help="validation dataset folder (holds labels.csv)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--junction-weight", type=float, default=1.0,
                   help="draw samples at junctions (relabel's junction column) this many times as often")
    p.add_argument("--obstacle-weight", type=float, default=1.0,
                   help="draw samples passing an obstacle (relabel's obstacle column) this many times as often")
    p.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--keep-epochs", action="store_true",
                   help="also write every epoch's weights to OUT/epochs/NN.pt (to choose by closed loop or average)")
    p.add_argument("--force", action="store_true", help="overwrite a model trained with other settings")


def refusing(run) -> int:
    """run(), with a TrainError as the command's refusal: its message, exit status 2."""
    try:
        run()
    except TrainError as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving_train", description=__doc__.split("\n\n")[0])
    add_shared_arguments(p)
    p.add_argument("--epochs", type=int, default=50)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--lr", type=float, default=5e-5)
    p.add_argument("--patience", type=int, default=5, help="epochs without a better val loss before stopping (0: never)")
    p.add_argument("--downscale", type=int, default=2, choices=(1, 2), help="2: train at 90x160")
    p.add_argument("--goal", action="store_true", help="feed labels.csv's goal column to the model")
    p.add_argument("--max-samples", type=int, default=0, help="rows of each labels.csv at most (0: all)")
    p.add_argument("--max-minutes", type=float, default=0.0,
                   help="stop after the epoch that passes this much training time (0: no limit)")
    p.add_argument("--init", default="", help="start from this model.pt's weights instead of random ones")
    p.add_argument("--input-norm", default="fixed", choices=tuple(NORMALISATIONS),
                   help="fixed: x / 255 - 0.5; image: each image's own mean and spread (InstanceNormalization)")
    p.add_argument("--augment", type=float, default=0.0,
                   help="condition augmentation's strength (sim4cv.driving_augment; 0: off, 1: its full ranges)")
    a = p.parse_args(argv)
    return refusing(lambda: train(
        a.train, a.val, a.out, epochs=a.epochs, batch=a.batch, lr=a.lr, patience=a.patience, downscale=a.downscale,
        goal=a.goal, max_samples=a.max_samples, threads=a.threads, force=a.force, seed=a.seed,
        max_minutes=a.max_minutes, init=a.init, junction_weight=a.junction_weight,
        obstacle_weight=a.obstacle_weight, keep_epochs=a.keep_epochs, input_norm=a.input_norm, augment=a.augment,
        log=lambda m: print(m, flush=True)))


if __name__ == "__main__":
    sys.exit(main())
