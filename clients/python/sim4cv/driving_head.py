"""Trains only the fully connected layers of a trained WaypointNet
(docs/driving.md, "Training the head alone"): the convolutions stay those of
--init, so what the model sees does not change, and only how it maps what it
sees to waypoints moves. Each image's features (WaypointNet.encode) are
computed once and, with --cache, kept on disk, so an epoch over 200,000
samples takes seconds instead of a quarter of an hour, and several learning
rates or weights can be tried on the same data.

    python3 -m sim4cv.driving head --init MODEL.pt --train DIR [DIR ...] --val DIR --out OUT \\
        [--epochs 20] [--batch 256] [--lr 1e-4] [--junction-weight K] [--obstacle-weight K] \\
        [--right-turn-weight K] [--cache DIR] [--threads N] [--seed 0] [--keep-epochs] [--last] [--force]

Writes what `train` writes (OUT/model.pt, model.onnx, training.json; the
best validation epoch; with --keep-epochs every epoch's OUT/epochs/NN.pt), so
evaluate, average and probe take its models as they are; with --last,
model.pt and model.onnx are the last epoch's. Refusals (exit
status 2, "error: ..."): those of `train`, and an --init that is not a
model.pt of `train`.
"""

import argparse
import copy
import hashlib
import io
import os
import pickle
import sys
import time
from typing import List, Optional

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset, WeightedRandomSampler

from sim4cv.driving_train import (DrivingDataset, TrainError, _check_out, _order, _save, _write,
                                  add_shared_arguments, check_run, model_from, record_weights, refusing)
from sim4cv.driving_weights import load_saved

# what makes two head models different (a rerun with other ones is refused unless --force)
HEAD_SETTINGS = ("train", "val", "epochs", "batch", "lr", "init", "junction_weight", "obstacle_weight",
                 "right_turn_weight")


class _Images(Dataset):
    """A dataset's images, decoded on every read (none kept: encode keeps the features)."""

    def __init__(self, part: DrivingDataset):
        self.part = part

    def __len__(self):
        return len(self.part)

    def __getitem__(self, i):
        return torch.from_numpy(self.part._read(i)).float()


def encode(model, part: DrivingDataset, cache: str, model_digest: str, log=print) -> torch.Tensor:
    """The features of every image of `part` under `model` (N x F float32),
    read from `cache` when a file there was made from the same labels.csv,
    image size and model; computed and written there otherwise."""
    labels = os.path.join(part.folder, "labels.csv")
    stat = os.stat(labels)
    key = "%s|%d|%d|%dx%d|%s" % (os.path.abspath(part.folder), stat.st_size, int(stat.st_mtime),
                                 part.height, part.width, model_digest)
    path = os.path.join(cache, hashlib.sha1(key.encode()).hexdigest()[:20] + ".npy") if cache else ""
    if path and os.path.isfile(path):
        features = np.load(path)
        if features.shape[0] == len(part):
            return torch.from_numpy(features)
    t0 = time.time()
    loader = DataLoader(_Images(part), batch_size=64, shuffle=False, num_workers=1)
    chunks = []
    with torch.no_grad():
        for images in loader:
            chunks.append(model.encode(images))
    features = torch.cat(chunks).contiguous()
    log("encoded %d images of %s in %.0f s" % (len(part), part.folder, time.time() - t0))
    if path:
        os.makedirs(cache, exist_ok=True)
        np.save(path + ".tmp.npy", features.numpy())
        os.replace(path + ".tmp.npy", path)  # a killed run leaves no half-written cache
    return features


def _loss(model, features, goals, targets, use_goal, batch=4096) -> float:
    model.eval()
    total = 0.0
    with torch.no_grad():
        for s in range(0, len(features), batch):
            out = model.head(features[s:s + batch], goals[s:s + batch] if use_goal else None)
            total += float(torch.nn.functional.mse_loss(out, targets[s:s + batch], reduction="sum"))
    return total / max(len(features), 1) / targets.shape[1]


def _right_turns(order: dict, parts, folders, goals, k: float, gen) -> dict:
    """`order` with the junction samples whose goal is a right turn drawn k
    times as often again: the turns the paper-sized maps' anticlockwise
    loops hardly hold (docs/driving.md, "Where the shipped model errs")."""
    missing = [f for f, part in zip(folders, parts) if part.flags["junction"] is None]
    if missing:
        raise TrainError("--right-turn-weight needs the junction column of `relabel`; %s has none"
                         % ", ".join(missing))
    draw = order["sampler"].weights.numpy() if "sampler" in order else np.ones(len(goals))
    right = np.concatenate([part.flags["junction"] for part in parts]) & (goals.numpy().reshape(-1) > 0.5)
    draw = draw * np.where(right, k, 1.0)
    return dict(sampler=WeightedRandomSampler(torch.from_numpy(draw), len(draw), replacement=True, generator=gen))


def train_head(init: str, train_dirs: List[str], val_dir: str, out: str, epochs: int = 20, batch: int = 256,
               lr: float = 1e-4, junction_weight: float = 1.0, obstacle_weight: float = 1.0,
               right_turn_weight: float = 1.0, cache: str = "",
               threads: int = 0, seed: int = 0, keep_epochs: bool = False, last: bool = False,
               force: bool = False, log=print) -> dict:
    weights = {"junction": junction_weight, "obstacle": obstacle_weight}
    check_run(epochs, batch, lr, dict(weights, right_turn=right_turn_weight))
    try:
        with open(init, "rb") as f:
            data = f.read()  # read once: loaded, and its digest keys the feature cache
        stored = load_saved(io.BytesIO(data), init)
        model, saved = model_from(stored), stored["settings"]
    except (OSError, KeyError, RuntimeError, EOFError, pickle.UnpicklingError) as e:
        raise TrainError("--init %s: not a model.pt of `train` (%s)" % (init, e))
    downscale = saved.get("downscale", 2)
    settings = dict(saved, train=[os.path.abspath(d) for d in train_dirs], val=os.path.abspath(val_dir),
                    epochs=epochs, batch=batch, lr=lr, init=os.path.abspath(init), head_only=True, seed=seed,
                    threads=threads)
    record_weights(settings, dict(weights, right_turn=right_turn_weight))
    parts = [DrivingDataset(d, downscale) for d in train_dirs]
    val = DrivingDataset(val_dir, downscale)
    if (parts[0].height, parts[0].width) != (model.height, model.width):
        raise TrainError("--init %s takes %dx%d images, the datasets give %dx%d"
                         % (init, model.height, model.width, parts[0].height, parts[0].width))
    _check_out(out, settings, force, HEAD_SETTINGS)
    os.makedirs(out, exist_ok=True)
    if threads > 0:
        torch.set_num_threads(threads)
    torch.manual_seed(seed)
    digest = hashlib.sha1(data).hexdigest()
    features = torch.cat([encode(model, p, cache, digest, log) for p in parts])
    goals = torch.from_numpy(np.concatenate([p.goals for p in parts]))
    targets = torch.from_numpy(np.concatenate([p.targets for p in parts]))
    val_features = encode(model, val, cache, digest, log)
    val_goals, val_targets = torch.from_numpy(val.goals), torch.from_numpy(val.targets)
    settings.update(train_samples=len(features), val_samples=len(val_features))
    use_goal = model.use_goal
    gen = torch.Generator()
    gen.manual_seed(seed)
    order = _order(parts, train_dirs, weights, gen)
    if right_turn_weight != 1.0:
        order = _right_turns(order, parts, train_dirs, goals, right_turn_weight, gen)
    opt = torch.optim.Adam(list(model.fc1.parameters()) + list(model.fc2.parameters()), lr=lr)
    best, best_epoch = _loss(model, val_features, val_goals, val_targets, use_goal), 0
    best_state, history = copy.deepcopy(model.state_dict()), []
    log("head: %d samples, validation %d; the init model's validation loss %.5f"
        % (len(features), len(val_features), best))
    for epoch in range(1, epochs + 1):
        t0 = time.time()
        model.train()
        index = (torch.tensor(list(iter(order["sampler"]))) if "sampler" in order
                 else torch.randperm(len(features), generator=gen))
        total = 0.0
        for s in range(0, len(index), batch):
            i = index[s:s + batch]
            opt.zero_grad()
            loss = torch.nn.functional.mse_loss(model.head(features[i], goals[i] if use_goal else None), targets[i])
            loss.backward()
            opt.step()
            total += float(loss) * len(i)
        val_loss = _loss(model, val_features, val_goals, val_targets, use_goal)
        seconds = time.time() - t0
        history.append(dict(epoch=epoch, train_loss=total / len(index), val_loss=val_loss, seconds=seconds,
                            train_samples_per_s=len(index) / seconds))
        if keep_epochs:
            _save(os.path.join(out, "epochs", "%02d.pt" % epoch), model.state_dict(), settings, epoch)
        improved = val_loss < best
        if improved:
            best, best_epoch, best_state = val_loss, epoch, copy.deepcopy(model.state_dict())
        log("epoch %d/%d: train %.5f  val %.5f%s  %.1f s" % (epoch, epochs, total / len(index), val_loss,
                                                         " (best)" if improved else "", seconds))
    if last:  # chosen in closed loop: the validation loss mixes in the ±4 m views the car never drives
        best, best_epoch, best_state = history[-1]["val_loss"], epochs, copy.deepcopy(model.state_dict())
    meta = _write(out, model, best_state, settings, history, best_epoch, best, epochs, finished=True)
    log("%s epoch %d (val %.5f; 0 is the init model); wrote %s"
        % ("last" if last else "best", best_epoch, best, out))
    return meta


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving head", description=__doc__.split("\n\n")[0])
    p.add_argument("--init", required=True, help="the trained model.pt whose convolutions are kept")
    add_shared_arguments(p)
    p.add_argument("--epochs", type=int, default=20)
    p.add_argument("--batch", type=int, default=256)
    p.add_argument("--lr", type=float, default=1e-4)
    p.add_argument("--right-turn-weight", type=float, default=1.0,
                   help="draw junction samples whose goal is a right turn (+1) this many times as often again")
    p.add_argument("--cache", default="", help="folder keeping each dataset's features for the next run")
    p.add_argument("--last", action="store_true",
                   help="model.pt/onnx from the last epoch, not the one of lowest validation loss")
    a = p.parse_args(argv)
    return refusing(lambda: train_head(
        a.init, a.train, a.val, a.out, epochs=a.epochs, batch=a.batch, lr=a.lr, junction_weight=a.junction_weight,
        obstacle_weight=a.obstacle_weight, right_turn_weight=a.right_turn_weight, cache=a.cache,
        threads=a.threads, seed=a.seed, keep_epochs=a.keep_epochs, last=a.last, force=a.force,
        log=lambda m: print(m, flush=True)))


if __name__ == "__main__":
    sys.exit(main())
