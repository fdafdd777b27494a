"""sim4cv.driving_train on a tiny real dataset (the real sim4cvd renders it,
as in test_driving_dataset.py): 2 epochs at 90x160, training.json, the ONNX
export through OpenCV, and the refusals."""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

torch = pytest.importorskip("torch")

from sim4cv import driving_card as dcard  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_net as dn  # noqa: E402
from sim4cv import driving_train as dt  # noqa: E402


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("driving") / "ds"
    dd.generate(maps=[os.path.join(REPO_ROOT, "scenes", "driving", "val", "01_desert.map")],
                surroundings=["desert"], out=str(out), views="random", random_views=2, max_samples=6,
                log=lambda *a: None)
    return out


def test_train_two_epochs_and_export(dataset, tmp_path):
    out = tmp_path / "model"
    logs = []
    meta = dt.train(str(dataset), str(dataset), str(out), epochs=2, batch=8, downscale=2, threads=2,
                    log=logs.append)
    assert sum(line.startswith("epoch ") for line in logs) == 2
    with open(out / "training.json") as f:
        stored = json.load(f)
    assert stored == json.loads(json.dumps(meta))
    assert len(stored["epochs"]) == 2 and stored["best_epoch"] in (1, 2)
    for e in stored["epochs"]:
        assert math.isfinite(e["train_loss"]) and math.isfinite(e["val_loss"])
        assert e["train_samples_per_s"] > 0 and e["seconds"] > 0
    s = stored["settings"]
    assert (s["height"], s["width"], s["downscale"], s["train_samples"]) == (90, 160, 2, 18)
    # the model card beside it: the network's contract, the paper's controller, not yet selected
    card = dcard.read(str(out / "model.onnx"))
    assert (card["input"]["height"], card["input"]["width"], card["input"]["goal"]) == (90, 160, False)
    assert card["input"]["channels"] == "RGB" and card["controller"]["steer_waypoint"] == 1
    assert card["selected"]["status"].startswith("not selected")

    model = dt.load_model(str(out / "model.pt"))
    run = dn.load_onnx_with_opencv(str(out / "model.onnx"), use_goal=False)
    ds = dt.DrivingDataset(str(dataset), downscale=2)
    image, _, _ = ds[0]
    got = run(image.numpy().transpose(1, 2, 0).astype(np.uint8))
    assert got.shape == (8,) and np.all(np.isfinite(got))
    with torch.no_grad():
        want = model(image[None]).numpy().reshape(-1)
    assert np.allclose(got, want, atol=1e-3)

    # the same OUT with other settings is refused, --force overrides
    with pytest.raises(dt.TrainError, match="other settings.*lr"):
        dt.train(str(dataset), str(dataset), str(out), epochs=2, batch=8, lr=1e-3, log=lambda *a: None)


def test_junction_and_obstacle_weights_draw_flagged_samples_more_often(dataset, tmp_path):
    with pytest.raises(dt.TrainError, match="junction column of `relabel`"):
        dt.train(str(dataset), str(dataset), str(tmp_path / "m"), epochs=1, junction_weight=5.0, log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="obstacle column of `relabel`"):
        dt.train(str(dataset), str(dataset), str(tmp_path / "m"), epochs=1, obstacle_weight=5.0, log=lambda *a: None)
    relabelled = tmp_path / "relabelled"
    relabelled.mkdir()
    with open(dataset / "labels.csv") as f:
        lines = f.read().splitlines()
    # the first sample's views marked as at a junction, the second's as passing an obstacle
    rows = [line + (",%d,%d" % (line.split(",")[4] == "0", line.split(",")[4] == "1") if i else ",junction,obstacle")
            for i, line in enumerate(lines)]
    (relabelled / "labels.csv").write_text("\n".join(rows) + "\n")
    os.symlink(dataset / "images", relabelled / "images")
    parts = [dt.DrivingDataset(str(relabelled))]
    junction, obstacle = parts[0].flags["junction"], parts[0].flags["obstacle"]
    assert 0 < junction.sum() < len(junction) and 0 < obstacle.sum() < len(obstacle)
    assert not np.any(junction & obstacle)
    assert dt._order(parts, [str(relabelled)], {"junction": 1.0, "obstacle": 1.0}, None) == dict(shuffle=True)
    for kj, ko in ((50.0, 1.0), (1.0, 50.0), (20.0, 40.0)):
        draws = dt._order(parts, [str(relabelled)], {"junction": kj, "obstacle": ko},
                          torch.Generator().manual_seed(0))["sampler"]
        drawn = np.array(list(draws))
        assert len(drawn) == len(junction)
        total = kj * junction.sum() + ko * obstacle.sum() + (~junction & ~obstacle).sum()
        for flags, k in ((junction, kj), (obstacle, ko)):
            share, want = flags[drawn].mean(), k * flags.sum() / total
            assert abs(share - want) < 0.35, (kj, ko, share, want)
    meta = dt.train(str(relabelled), str(relabelled), str(tmp_path / "w"), epochs=1, batch=8, junction_weight=50.0,
                    obstacle_weight=3.0, log=lambda *a: None)
    assert meta["settings"]["junction_weight"] == 50.0 and meta["settings"]["obstacle_weight"] == 3.0
    with pytest.raises(dt.TrainError, match="--junction-weight must be >= 1"):
        dt.train(str(relabelled), str(relabelled), str(tmp_path / "x"), junction_weight=0.5, log=lambda *a: None)
    with pytest.raises(dt.TrainError, match="--obstacle-weight must be >= 1"):
        dt.train(str(relabelled), str(relabelled), str(tmp_path / "x"), obstacle_weight=0.0, log=lambda *a: None)


def test_refusals(dataset, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    r = subprocess.run([sys.executable, "-m", "sim4cv.driving_train", "--train", str(empty), "--val",
                        str(dataset), "--out", str(tmp_path / "o")], capture_output=True, text=True,
                       cwd=os.path.join(REPO_ROOT, "clients", "python"))
    assert r.returncode == 2 and "no labels.csv" in r.stderr and str(empty) in r.stderr
    assert not (tmp_path / "o").exists()

    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "labels.csv").write_text("image,v1,h1\nx.png,2,0\n")
    assert dt.main(["--train", str(bad), "--val", str(dataset), "--out", str(tmp_path / "o")]) == 2
    with pytest.raises(dt.TrainError, match="missing columns: v2"):
        dt.read_labels(str(bad))


def test_training_goes_on_from_a_model_and_refuses_another_size(dataset, tmp_path):
    first = tmp_path / "first"
    dt.train(str(dataset), str(dataset), str(first), epochs=1, batch=8, downscale=2, threads=2, log=lambda *a: None)
    start = dt.load_model(str(first / "model.pt"))
    # lr tiny: one more epoch from the first model's weights keeps them close to where they started
    meta = dt.train(str(dataset), str(dataset), str(tmp_path / "second"), epochs=1, batch=8, lr=1e-12, downscale=2,
                    threads=2, init=str(first / "model.pt"), log=lambda *a: None)
    assert meta["settings"]["init"] == str(first / "model.pt")
    second = dt.load_model(str(tmp_path / "second" / "model.pt"))
    for a, b in zip(start.state_dict().values(), second.state_dict().values()):
        assert torch.allclose(a, b, atol=1e-6)
    with pytest.raises(dt.TrainError, match=r"--init .* was trained at 90x160 goal=False input norm fixed, not 180x320 goal=False"):
        dt.train(str(dataset), str(dataset), str(tmp_path / "third"), epochs=1, downscale=1,
                 init=str(first / "model.pt"), log=lambda *a: None)


def test_a_goal_model_starts_from_a_lane_model_with_the_same_outputs(dataset, tmp_path):
    first = tmp_path / "first"
    dt.train(str(dataset), str(dataset), str(first), epochs=1, batch=8, downscale=2, threads=2, log=lambda *a: None)
    dt.train(str(dataset), str(dataset), str(tmp_path / "goal"), epochs=1, batch=8, lr=1e-12, downscale=2,
             threads=2, goal=True, init=str(first / "model.pt"), log=lambda *a: None)
    lane, guided = dt.load_model(str(first / "model.pt")), dt.load_model(str(tmp_path / "goal" / "model.pt"))
    image = torch.rand(2, 3, 90, 160) * 255
    assert torch.allclose(lane(image), guided(image, torch.tensor([[1.0], [-1.0]])), atol=1e-4)
    with pytest.raises(dt.TrainError, match="goal=True input norm fixed, not 90x160 goal=False"):
        dt.train(str(dataset), str(dataset), str(tmp_path / "back"), epochs=1, downscale=2,
                 init=str(tmp_path / "goal" / "model.pt"), log=lambda *a: None)


def test_an_image_normalised_model_starts_from_a_fixed_one_and_its_card_says_so(dataset, tmp_path):
    first = tmp_path / "first"
    dt.train(str(dataset), str(dataset), str(first), epochs=1, batch=8, downscale=2, threads=2, log=lambda *a: None)
    out = tmp_path / "robust"
    meta = dt.train(str(dataset), str(dataset), str(out), epochs=1, batch=8, lr=1e-12, downscale=2, threads=2,
                    init=str(first / "model.pt"), input_norm="image", augment=1.0, log=lambda *a: None)
    assert meta["settings"]["input_norm"] == "image" and meta["settings"]["augment"] == 1.0
    assert "input_norm" not in json.load(open(first / "training.json"))["settings"]  # the default is not recorded
    robust = dt.load_model(str(out / "model.pt"))
    assert robust.input_norm == "image"
    assert torch.allclose(robust.norm.weight, torch.full((3,), dn.IMAGE_NORM_SCALE))
    assert "InstanceNormalization" in dcard.read(str(out / "model.onnx"))["input"]["normalisation"]
    with pytest.raises(dt.TrainError, match="input norm image, not 90x160 goal=False input norm fixed"):
        dt.train(str(dataset), str(dataset), str(tmp_path / "back"), epochs=1, downscale=2,
                 init=str(out / "model.pt"), log=lambda *a: None)


def test_kept_epochs_average_into_one_model_with_the_mean_weights(dataset, tmp_path):
    from sim4cv import driving_average as da
    out = tmp_path / "run"
    dt.train(str(dataset), str(dataset), str(out), epochs=2, batch=8, lr=1e-3, downscale=2, threads=2,
             goal=True, keep_epochs=True, log=lambda *a: None)
    epochs = [str(out / "epochs" / "01.pt"), str(out / "epochs" / "02.pt")]
    one, two = (dt.load_model(p) for p in epochs)
    assert not torch.equal(one.fc2.weight, two.fc2.weight)  # lr 1e-3: the epochs differ
    meta = da.average(epochs, str(tmp_path / "avg"), log=lambda *a: None)
    assert meta["models"] == epochs and meta["goal"] is True
    avg = dt.load_model(str(tmp_path / "avg" / "model.pt"))
    for name, value in avg.state_dict().items():
        assert torch.allclose(value, (one.state_dict()[name] + two.state_dict()[name]) / 2)
    image = torch.rand(1, 3, 90, 160) * 255
    run = dn.load_onnx_with_opencv(str(tmp_path / "avg" / "model.onnx"), use_goal=True)
    with torch.no_grad():
        want = avg(image, torch.tensor([[1.0]])).numpy().reshape(-1)
    assert np.allclose(run(image[0].numpy().transpose(1, 2, 0), 1.0), want, atol=1e-3)

    # refusals: one model, a file that is no model, another architecture
    with pytest.raises(da.AverageError, match="at least 2 models, got 1"):
        da.average(epochs[:1], str(tmp_path / "x"), log=lambda *a: None)
    (tmp_path / "junk.pt").write_bytes(b"not a model")
    with pytest.raises(da.AverageError, match="junk.pt: not a model.pt"):
        da.average([epochs[0], str(tmp_path / "junk.pt")], str(tmp_path / "x"), log=lambda *a: None)
    dt.train(str(dataset), str(dataset), str(tmp_path / "lane"), epochs=1, batch=8, downscale=2, threads=2,
             log=lambda *a: None)
    with pytest.raises(da.AverageError, match="90x160 goal=True, .* has 90x160 goal=False"):
        da.average([epochs[0], str(tmp_path / "lane" / "model.pt")], str(tmp_path / "x"), log=lambda *a: None)
    assert subprocess.run([sys.executable, "-m", "sim4cv.driving", "average", "--models", epochs[0],
                           "--out", str(tmp_path / "x")], cwd=os.path.join(REPO_ROOT, "clients", "python"),
                          capture_output=True, text=True).stderr.startswith("error: average needs at least 2")


def test_probe_puts_the_models_waypoints_beside_the_labels(dataset, tmp_path, capsys):
    import csv
    from sim4cv import driving_probe as dp
    from sim4cv.driving import main as driving_main
    out = tmp_path / "run"
    dt.train(str(dataset), str(dataset), str(out), epochs=1, batch=8, downscale=2, threads=2, goal=True,
             log=lambda *a: None)
    model = dt.load_model(str(out / "model.pt"))
    with open(dataset / "labels.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    lane = dp.select(rows, "driving_val_01_desert", (1, 3), lane_only=True)
    assert [int(r["sample"]) for r in lane] == [1, 2, 3]  # one lane view per sample, the random views left out
    assert len(dp.select(rows, samples=(1, 3))) == 9 and dp.select(rows, "no_such_map") == []

    from sim4cv.driving_eval import NetworkPolicy
    result = dp.probe(NetworkPolicy(str(out / "model.pt")), str(dataset), lane)
    ds = dt.DrivingDataset(str(dataset), downscale=2)
    errors = []
    for row in result["rows"]:
        image, goal, label = ds[[r["image"] for r in ds.rows].index(row["image"])]
        with torch.no_grad():
            want = model(image[None], goal[None]).numpy().reshape(-1)
        got = [row["pred_" + k] for k in ("v1", "h1", "v2", "h2", "v3", "h3", "v4", "h4")]
        assert np.allclose(got, want, atol=1e-3)  # the closed loop's inference on the stored image
        assert np.allclose([float(row[k]) for k in ("h1", "h2", "h3", "h4")], label.numpy()[1::2], atol=1e-4)
        errors.append(np.abs(np.array(got[1::2]) - label.numpy()[1::2]))
    assert np.allclose([result["mae_h"][h] for h in dp.H], np.mean(errors, axis=0), atol=1e-3)
    assert sum(g["images"] for g in result["h2_by_group"].values()) == 3
    mean_h2 = sum(e["mean_error_m"] * e["images"] for e in result["h2_by_group"].values()) / 3
    assert mean_h2 == pytest.approx(np.mean([r["pred_h2"] - float(r["h2"]) for r in result["rows"]]))
    assert dp.group({"h2": "0.5", "junction": "1"}) == "right turn at junction"
    assert dp.group({"h2": "-0.31", "junction": "0"}) == "left turn"
    assert dp.group({"h2": "0.3"}) == "straight"

    # the command: the lines, the summary, the CSV; and its refusals with their messages
    csv_out = tmp_path / "probe.csv"
    assert driving_main(["probe", "--model", str(out / "model.onnx"), "--dataset", str(dataset),
                         "--samples", "1:3", "--lane-only", "--out", str(csv_out)]) == 0
    with open(csv_out, newline="") as f:
        assert len(list(csv.DictReader(f))) == 3
    with pytest.raises(dp.ProbeError, match="--samples 3-1: expected FIRST:LAST"):
        dp.parse_samples("3-1")
    with pytest.raises(dp.ProbeError, match="--samples 3:1: FIRST is after LAST"):
        dp.parse_samples("3:1")
    capsys.readouterr()
    assert driving_main(["probe", "--model", str(out / "model.onnx"), "--dataset", str(tmp_path)]) == 2
    assert "has no labels.csv" in capsys.readouterr().err
    assert driving_main(["probe", "--model", str(out / "model.onnx"), "--dataset", str(dataset),
                         "--map", "no_such_map"]) == 2
    assert "matches --map 'no_such_map'" in capsys.readouterr().err
