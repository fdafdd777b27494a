"""Bad models and maps given to the driving tools: a model whose outputs are
NaN stops the run naming the model and the frame; empty, truncated and
code-carrying model files are refused with a message; a valid map without
a tile_size line is read as the daemon reads it; a refused run leaves no
empty folders."""

import os
import subprocess
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PYTHON_DIR = os.path.join(REPO_ROOT, "clients", "python")
sys.path.insert(0, PYTHON_DIR)

from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_eval as de  # noqa: E402

SHIPPED = os.path.join(REPO_ROOT, "models", "driving")
TEST_MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_desert.map")


def _evaluate(*args, timeout=240):
    return subprocess.run([sys.executable, "-m", "sim4cv.driving", "evaluate", *args], cwd=PYTHON_DIR,
                          capture_output=True, text=True, timeout=timeout)


def test_a_model_giving_nan_stops_the_run_naming_the_model_and_the_frame(tmp_path):
    torch = pytest.importorskip("torch")
    from sim4cv.driving_net import WaypointNet, export_onnx
    net = WaypointNet(90, 160).eval()
    with torch.no_grad():
        net.fc2.bias[3] = float("nan")  # h2, the waypoint the shipped card steers at
    model = str(tmp_path / "nan.onnx")
    export_onnx(net, model)
    out = tmp_path / "eval"
    r = _evaluate("--model", model, "--maps", TEST_MAP, "--out", str(out))
    assert r.returncode == 2, r.stdout + r.stderr
    assert ("error: model %s gave non-finite waypoints [" % model) in r.stderr
    assert ", nan, " in r.stderr and "at frame 1 (0.00 s) of route loop on driving_test_01_desert: stopped" in r.stderr
    assert not out.exists()  # stopped before any lap was written: no empty OUT/runs


def test_infinite_waypoints_are_refused_too():
    policy = de.ReferencePolicy()
    with pytest.raises(de.EvalError, match=r"policy reference gave non-finite waypoints \[2, 0, inf, .*at frame 7"):
        de.check_waypoints([2.0, 0.0, float("inf"), 0.0, 6.0, 0.0, 8.0, 0.0], policy, "frame 7")
    de.check_waypoints([2.0, 0.1, 4.0, 0.2, 6.0, 0.3, 8.0, 0.4], policy, "frame 8")


def test_empty_and_truncated_model_files_get_a_clear_message(tmp_path):
    for suffix in ("onnx", "pt"):
        empty = tmp_path / ("empty." + suffix)
        empty.write_bytes(b"")
        with pytest.raises(de.EvalError, match=r"model file .*empty\.%s is empty \(0 bytes\)" % suffix):
            de.NetworkPolicy(str(empty))
    data = open(os.path.join(SHIPPED, "model.onnx"), "rb").read()
    truncated = tmp_path / "truncated.onnx"
    truncated.write_bytes(data[:len(data) // 2])
    with pytest.raises(de.EvalError, match=r"truncated\.onnx is not a readable ONNX model"):
        de.NetworkPolicy(str(truncated))
    pytest.importorskip("torch")
    data = open(os.path.join(SHIPPED, "model.pt"), "rb").read()
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(data[:len(data) // 2])
    with pytest.raises(de.EvalError, match=r"truncated\.pt: not a model\.pt of `train` \(torch's zip format; "
                                           r"empty or truncated\?\)"):
        de.NetworkPolicy(str(truncated))


def test_a_model_pt_that_would_run_code_is_refused_unloaded(tmp_path):
    torch = pytest.importorskip("torch")
    from sim4cv import driving_train as dt
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return (os.system, ("touch '%s'" % marker,))

    evil = tmp_path / "model.pt"
    torch.save({"settings": Payload(), "state_dict": {}}, str(evil))
    from sim4cv.driving_weights import WeightsError
    with pytest.raises(WeightsError, match=r"model\.pt: refers to posix\.system; a model\.pt holds only tensors"):
        dt.load_model(str(evil))
    r = _evaluate("--model", str(evil), "--maps", TEST_MAP, "--out", str(tmp_path / "eval"), timeout=60)
    assert r.returncode == 2 and "refers to posix.system" in r.stderr
    assert not marker.exists() and not (tmp_path / "eval").exists()
    assert dt.load_model(os.path.join(SHIPPED, "model.pt")).use_goal  # the shipped one still loads


def _without_tile_size(tmp_path):
    text = open(TEST_MAP).read()
    assert "\ntile_size 20\n" in text
    path = tmp_path / "no_tile_size.map"
    path.write_text(text.replace("\ntile_size 20\n", "\n"))
    return str(path)


def test_a_map_without_tile_size_is_read_with_the_default_20(tmp_path):
    from sim4cv.driving_guided import RoadGrid
    path = _without_tile_size(tmp_path)
    with_line, without = dd.parse_map(TEST_MAP), dd.parse_map(path)
    assert without["tile_size"] == 20.0
    assert {k: v for k, v in without.items() if k != "path"} == {k: v for k, v in with_line.items() if k != "path"}
    assert RoadGrid.from_map(path).conn == RoadGrid.from_map(TEST_MAP).conn
    out = tmp_path / "eval"
    r = _evaluate("--policy", "reference", "--maps", path, "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert "1 runs, 1 completed" in r.stdout


def test_a_refused_map_leaves_no_folder(tmp_path):
    bad = tmp_path / "bad.map"
    bad.write_text("sim4cv-map 1\nname broken\ngrid 3 2\n###\n")
    out = tmp_path / "eval"
    r = _evaluate("--policy", "reference", "--maps", str(bad), "--out", str(out), timeout=60)
    assert r.returncode == 2 and "bad.map: the grid ends after 1 of its 2 rows" in r.stderr
    assert not out.exists()
