"""sim4cv.driving_head on a tiny real dataset (the real sim4cvd renders it):
only the fully connected layers move, the features are cached and reused,
the outputs are train's, and the refusals carry their messages."""

import json
import os
import sys

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

torch = pytest.importorskip("torch")

from sim4cv import driving_card as dcard  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_head as dh  # noqa: E402
from sim4cv import driving_net as dn  # noqa: E402
from sim4cv import driving_train as dt  # noqa: E402
from sim4cv.driving import main as driving_main  # noqa: E402


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("head")
    dd.generate(maps=[os.path.join(REPO_ROOT, "scenes", "driving", "val", "01_desert.map")],
                surroundings=["desert"], out=str(root / "ds"), views="random", random_views=2, max_samples=6,
                log=lambda *a: None)
    dt.train(str(root / "ds"), str(root / "ds"), str(root / "init"), epochs=1, batch=8, goal=True, threads=2,
             log=lambda *a: None)
    return root


def test_only_the_head_moves_and_the_features_are_cached(trained, tmp_path):
    ds, init = str(trained / "ds"), str(trained / "init" / "model.pt")
    logs = []
    meta = dh.train_head(init, [ds], ds, str(tmp_path / "m"), epochs=3, batch=4, lr=1e-3, cache=str(tmp_path / "c"),
                         threads=2, keep_epochs=True, log=logs.append)
    # the validation set is the training set here: encoded once, read back from the cache the second time
    assert sum(line.startswith("encoded 18 images") for line in logs) == 1
    assert len(os.listdir(tmp_path / "c")) == 1
    before, after = dt.load_model(init), dt.load_model(str(tmp_path / "m" / "epochs" / "03.pt"))
    for name, value in before.state_dict().items():
        moved = not torch.equal(value, after.state_dict()[name])
        assert moved == name.startswith(("fc1.", "fc2.")), name
    with open(tmp_path / "m" / "training.json") as f:
        stored = json.load(f)
    assert stored == json.loads(json.dumps(meta)) and len(stored["epochs"]) == 3
    assert stored["settings"]["head_only"] and stored["settings"]["goal"] and stored["settings"]["train_samples"] == 18
    assert dcard.read(str(tmp_path / "m" / "model.pt"))["input"]["goal"] is True  # head writes the card too
    # model.pt is the best epoch by validation loss (0: the init model itself), model.onnx the same weights
    best = min([(e["val_loss"], e["epoch"]) for e in stored["epochs"]] + [(float("inf"), 0)])[1]
    assert stored["best_epoch"] == best
    model = dt.load_model(str(tmp_path / "m" / "model.pt"))
    image, goal, _ = dt.DrivingDataset(ds, downscale=2)[0]
    run = dn.load_onnx_with_opencv(str(tmp_path / "m" / "model.onnx"), use_goal=True)
    with torch.no_grad():
        want = model(image[None], goal[None]).numpy().reshape(-1)
        assert torch.allclose(model.encode(image[None]), before.encode(image[None]))
    assert np.allclose(run(image.numpy().transpose(1, 2, 0).astype(np.uint8), float(goal)), want, atol=1e-3)

    # a second run reads the features from the cache (no encoding) and gives the same model; with
    # last, model.pt is the last epoch whatever the validation loss
    logs.clear()
    meta = dh.train_head(init, [ds], ds, str(tmp_path / "m2"), epochs=3, batch=4, lr=1e-3, cache=str(tmp_path / "c"),
                         threads=2, keep_epochs=True, last=True, log=logs.append)
    assert not any(line.startswith("encoded") for line in logs)
    assert meta["best_epoch"] == 3 and logs[-1].startswith("last epoch 3")
    for name in ("epochs/03.pt", "model.pt"):
        again = dt.load_model(str(tmp_path / "m2" / name))
        assert all(torch.allclose(v, again.state_dict()[k], atol=1e-6) for k, v in after.state_dict().items())


def test_right_turns_at_junctions_are_drawn_k_times_as_often_again():
    from torch.utils.data import WeightedRandomSampler

    class Part:  # what _right_turns reads of a DrivingDataset: relabel's junction column
        def __init__(self, junction):
            self.flags = {"junction": None if junction is None else np.array(junction)}

    goals = torch.tensor([[1.0], [1.0], [-1.0], [1.0]])  # +1: the route turns right there
    parts = [Part([True, False]), Part([True, True])]
    order = dh._right_turns(dict(shuffle=True), parts, ["a", "b"], goals, 4.0, torch.Generator())
    assert order["sampler"].weights.tolist() == [4.0, 1.0, 1.0, 4.0]
    # on top of the junction weight (3): a right turn at a junction 12 times as likely as a straight sample
    weighted = dict(sampler=WeightedRandomSampler(torch.tensor([3.0, 1.0, 3.0, 3.0]), 4))
    assert dh._right_turns(weighted, parts, ["a", "b"], goals, 4.0, torch.Generator())["sampler"].weights.tolist() \
        == [12.0, 1.0, 3.0, 12.0]
    with pytest.raises(dt.TrainError, match="--right-turn-weight needs the junction column of `relabel`; b has none"):
        dh._right_turns(dict(shuffle=True), [Part([True, False]), Part(None)], ["a", "b"], goals, 4.0,
                        torch.Generator())


def test_refusals(trained, tmp_path, capsys):
    ds, init = str(trained / "ds"), str(trained / "init" / "model.pt")
    with pytest.raises(dt.TrainError, match="not a model.pt of `train`"):
        dh.train_head(str(tmp_path / "none.pt"), [ds], ds, str(tmp_path / "m"), log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="junction column of `relabel`"):
        dh.train_head(init, [ds], ds, str(tmp_path / "m"), junction_weight=3, log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="--junction-weight must be >= 1, got 0.5"):
        dh.train_head(init, [ds], ds, str(tmp_path / "m"), junction_weight=0.5, log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="--right-turn-weight must be >= 1, got 0"):
        dh.train_head(init, [ds], ds, str(tmp_path / "m"), right_turn_weight=0, log=lambda *a: None)
    dh.train_head(init, [ds], ds, str(tmp_path / "m"), epochs=1, log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="other settings.*lr"):
        dh.train_head(init, [ds], ds, str(tmp_path / "m"), epochs=1, lr=1e-2, log=lambda *a: None)
    assert driving_main(["head", "--init", init, "--train", ds, "--val", str(tmp_path), "--out",
                         str(tmp_path / "m3")]) == 2
    assert "has no labels.csv" in capsys.readouterr().err
