"""The driving case study's network (sim4cv.driving_net: shapes, goal,
training steps, ONNX export run by OpenCV's DNN) and controller
(sim4cv.driving_control, hand-computed cases). CPU only, a few seconds."""

import math
import os
import sys

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_control as dc  # noqa: E402

torch = pytest.importorskip("torch")
from sim4cv import driving_net as dn  # noqa: E402

SIZES = [(180, 320), (90, 160)]


def _images(n, h, w, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.randint(0, 256, (n, 3, h, w), generator=g).float()


@pytest.mark.parametrize("h,w", SIZES)
@pytest.mark.parametrize("use_goal", [False, True])
def test_output_shape(h, w, use_goal):
    torch.manual_seed(0)
    model = dn.WaypointNet(h, w, use_goal=use_goal).eval()
    x = _images(2, h, w)
    with torch.no_grad():
        out = model(x, torch.tensor([-1.0, 1.0]) if use_goal else None)
    assert out.shape == (2, 8)
    assert torch.isfinite(out).all()


def test_conv_sizes_and_pool_windows():
    assert dn.conv_output_size(180, 320) == (15, 33)
    assert dn.conv_output_size(90, 160) == (4, 13)
    assert dn.pool_window(15, 2) == (8, 7)   # windows [0, 8), [7, 15)
    assert dn.pool_window(4, 2) == (2, 2)    # torch's adaptive bins
    with pytest.raises(ValueError):
        dn.WaypointNet(40, 40)               # too small for the pooling


def test_goal_changes_output():
    torch.manual_seed(0)
    model = dn.WaypointNet(90, 160, use_goal=True).eval()
    x = _images(1, 90, 160).repeat(3, 1, 1, 1)
    with torch.no_grad():
        out = model(x, torch.tensor([-1.0, 0.0, 1.0]))
        none = model(x[:1])
    assert not torch.allclose(out[0], out[1]) and not torch.allclose(out[1], out[2])
    assert torch.allclose(none[0], out[1])  # a missing goal is 0
    with pytest.raises(ValueError):
        dn.WaypointNet(90, 160)(x[:1], torch.zeros(1))


def test_adam_reduces_l2_loss():
    torch.manual_seed(0)
    model = dn.WaypointNet(90, 160, use_goal=True)
    x = _images(4, 90, 160, seed=1)
    goal = torch.tensor([-1.0, 0.0, 0.0, 1.0])
    target = torch.tensor([[2.0, 0.1, 4.0, 0.4, 6.0, 0.9, 8.0, 1.6]]).repeat(4, 1)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    losses = []
    for _ in range(8):
        opt.zero_grad()
        loss = ((model(x, goal) - target) ** 2).sum(1).mean()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert losses[-1] < 0.5 * losses[0], losses


@pytest.mark.parametrize("h,w", SIZES)
@pytest.mark.parametrize("use_goal", [False, True])
def test_onnx_opencv_matches_torch(tmp_path, h, w, use_goal):
    torch.manual_seed(0)
    model = dn.WaypointNet(h, w, use_goal=use_goal)
    path = str(tmp_path / "net.onnx")
    dn.export_onnx(model, path, h, w)
    assert model.training  # export leaves the mode as it was
    model.eval()
    run = dn.load_onnx_with_opencv(path, use_goal=use_goal)
    rng = np.random.RandomState(3)
    for goal in ([-1.0, 1.0] if use_goal else [0.0]):
        img = rng.randint(0, 256, (h, w, 3), dtype=np.uint8)
        x = torch.from_numpy(img.transpose(2, 0, 1)[None].astype(np.float32))
        with torch.no_grad():
            ref = model(x, torch.tensor([[goal]]) if use_goal else None).numpy().reshape(-1)
        out = run(img, goal)
        assert out.shape == (8,)
        np.testing.assert_allclose(out, ref, atol=1e-4, rtol=0)


def test_image_normalisation_sees_a_darker_image_as_the_same_road_in_torch_and_opencv(tmp_path):
    torch.manual_seed(0)
    model = dn.WaypointNet(90, 160, use_goal=True, input_norm="image").eval()
    rng = np.random.RandomState(4)
    img = rng.randint(40, 216, (90, 160, 3), dtype=np.uint8)
    dark = (img.astype(np.float32) * 0.3 + 5).astype(np.uint8)   # night: a third of the light
    x = torch.from_numpy(np.stack([img, dark]).transpose(0, 3, 1, 2).astype(np.float32))
    with torch.no_grad():
        ref = model(x, torch.tensor([[1.0], [1.0]])).numpy()
    np.testing.assert_allclose(ref[0], ref[1], atol=2e-3, rtol=0)
    fixed = dn.WaypointNet(90, 160, use_goal=True).eval()
    fixed.load_state_dict({k: v for k, v in model.state_dict().items() if not k.startswith("norm.")})
    with torch.no_grad():
        seen = fixed(x, torch.tensor([[1.0], [1.0]])).numpy()
    assert np.abs(seen[0] - seen[1]).max() > 10 * np.abs(ref[0] - ref[1]).max()
    path = str(tmp_path / "image_norm.onnx")
    dn.export_onnx(model, path)
    run = dn.load_onnx_with_opencv(path, use_goal=True)
    np.testing.assert_allclose(run(img, 1.0), ref[0], atol=1e-4, rtol=0)
    with pytest.raises(ValueError, match="input_norm 'batch' is not one of fixed, image"):
        dn.WaypointNet(90, 160, input_norm="batch")


def test_onnx_contract(tmp_path):
    pytest.importorskip("onnx")
    path = str(tmp_path / "net.onnx")
    dn.export_onnx(dn.WaypointNet(90, 160, use_goal=True), path)
    assert list(dn.onnx_input_names(path)) == ["image", "goal"]
    import onnx
    m = onnx.load(path)
    dims = {i.name: [d.dim_value for d in i.type.tensor_type.shape.dim] for i in m.graph.input}
    assert dims["image"] == [1, 3, 90, 160] and dims["goal"] == [1, 1]
    assert [o.name for o in m.graph.output] == ["waypoints"]
    assert m.opset_import[0].version == 11
    dn.load_onnx_with_opencv(path)(np.zeros((90, 160, 3), np.uint8), 1.0)  # use_goal read from the file


# ---- controller ----

def test_straight_full_throttle():
    assert dc.controls_from_waypoints([2, 0, 4, 0, 6, 0, 8, 0]) == (0.0, 1.0, 0.0)


def test_point_to_the_right():
    # atan(0.5 / 2) = 14.036 deg; / 35 deg = 0.40104
    s = dc.steering_from_waypoint(2.0, 0.5)
    assert s == pytest.approx(math.degrees(math.atan(0.25)) / 35.0)
    assert s == pytest.approx(0.40104, abs=1e-5)
    assert dc.steering_from_waypoint(2.0, -0.5) == pytest.approx(-s)
    assert dc.steering_from_waypoint(2.0, 0.5, max_steering_deg=28.07) == pytest.approx(0.5, abs=1e-3)


def test_turn_lowers_throttle():
    # the labels of a right turn of radius 20 m (docs/driving.md): h4 = 1.58 -> 1 - 0.25 * 1.58 = 0.605
    s, t, b = dc.controls_from_waypoints([2.00, 0.10, 3.97, 0.40, 5.91, 0.89, 7.79, 1.58])
    assert t == pytest.approx(0.605) and b == 0.0 and s > 0
    assert dc.throttle_from_waypoint(-1.58) == pytest.approx(0.605)  # left turn: same
    assert dc.throttle_from_waypoint(5.0) == pytest.approx(0.3)      # floor t_min
    assert dc.throttle_from_waypoint(1.0, t_max=0.6, t_min=0.2, k=0.3) == pytest.approx(0.3)


def test_speed_cap():
    assert dc.throttle_from_waypoint(0.0, speed=9.9, max_speed=10.0) == 1.0
    assert dc.throttle_from_waypoint(0.0, speed=10.0, max_speed=10.0) == 0.0
    assert dc.controls_from_waypoints([2, 0, 4, 0, 6, 0, 8, 0], speed=12.0, max_speed=10.0)[1] == 0.0


def test_steering_clamped():
    assert dc.steering_from_waypoint(1.0, 5.0) == 1.0    # 78.7 deg > 35
    assert dc.steering_from_waypoint(1.0, -5.0) == -1.0
    assert dc.steering_from_waypoint(2.0, 0.5, gain=10.0) == 1.0


def test_v1_not_ahead():
    assert dc.steering_from_waypoint(0.0, 1.0) == 1.0
    assert dc.steering_from_waypoint(-2.0, -0.1) == -1.0
    assert dc.steering_from_waypoint(-2.0, 0.0) == 0.0
    assert dc.steering_from_waypoint(0.0, 0.0) == 0.0


def test_bad_arguments():
    with pytest.raises(ValueError):
        dc.controls_from_waypoints([2, 0, 4, 0])
    with pytest.raises(ValueError):
        dc.steering_from_waypoint(2, 0, max_steering_deg=0)
    with pytest.raises(ValueError):
        dc.throttle_from_waypoint(0, t_min=0.8, t_max=0.5)


def test_the_steering_may_aim_at_a_farther_waypoint():
    w = [2.0, 0.5, 4.0, 2.0, 6.0, 0.0, 8.0, 0.0]
    assert dc.controls_from_waypoints(w)[0] == pytest.approx(math.degrees(math.atan(0.25)) / 35.0)
    assert dc.controls_from_waypoints(w, steer_waypoint=2)[0] == pytest.approx(math.degrees(math.atan(0.5)) / 35.0)
    assert dc.controls_from_waypoints(w, steer_waypoint=3)[0] == 0.0
    with pytest.raises(ValueError, match="steer_waypoint must be 1 ... 4, got 5"):
        dc.controls_from_waypoints(w, steer_waypoint=5)


def test_turn_slowdown_lowers_the_cap_and_brakes_down_to_it():
    turn = [2.00, 0.10, 3.97, 0.40, 5.91, 0.89, 7.79, 1.58]  # the right turn of radius 20 m above
    # cap = 8 - 2 * 1.58 = 4.84 m/s: at 6 m/s no throttle and brake 0.5 * (6 - 4.84) = 0.58
    assert dc.turn_speed_cap(1.58, 8.0, 2.0) == pytest.approx(4.84)
    s, t, b = dc.controls_from_waypoints(turn, speed=6.0, max_speed=8.0, slowdown=2.0)
    assert s > 0 and t == 0.0 and b == pytest.approx(0.58)
    # below the cap: the paper's throttle rule, no brake
    assert dc.controls_from_waypoints(turn, speed=4.0, max_speed=8.0, slowdown=2.0)[1:] == (pytest.approx(0.605), 0.0)
    # the cap never falls below MIN_TURN_SPEED (4 m/s), nor above max_speed; the brake saturates at 1
    assert dc.turn_speed_cap(10.0, 8.0, 2.0) == dc.MIN_TURN_SPEED == 4.0
    assert dc.turn_speed_cap(10.0, 3.0, 2.0) == 3.0
    assert dc.controls_from_waypoints(turn, speed=20.0, max_speed=8.0, slowdown=2.0)[2] == 1.0
    # off (0, the default) or without a speed cap: brake 0 as before
    assert dc.controls_from_waypoints(turn, speed=20.0, max_speed=8.0)[2] == 0.0
    assert dc.controls_from_waypoints(turn, speed=20.0, slowdown=2.0)[2] == 0.0
    with pytest.raises(ValueError, match="slowdown must be >= 0, got -1"):
        dc.controls_from_waypoints(turn, speed=6.0, max_speed=8.0, slowdown=-1.0)


def test_bend_correction_moves_the_aim_point_out_of_a_bend():
    # waypoints on a right bend of radius 40 m (arc lengths 2, 4, 6, 8 m): the
    # circle through the first three has curvature 1/40; aimed at the second
    # (chord 80 sin(0.05) = 3.9933 m) the chord's offset from the arc is
    # kappa l^2 / 2 = 0.1998 m, and C = 0.2 moves the aim point 0.03997 m left.
    r = 40.0
    bend = [c for s in (2, 4, 6, 8) for c in (r * math.sin(s / r), r * (1 - math.cos(s / r)))]
    assert dc.bend_curvature(bend) == pytest.approx(1 / r, rel=1e-12)
    chord2 = (2 * r * math.sin(2 / r)) ** 2
    assert dc.bend_shift(bend, bend[2], bend[3], 0.2) == pytest.approx(-0.2 * chord2 / (2 * r), rel=1e-12)
    assert dc.bend_shift(bend, bend[2], bend[3], 0.2) == pytest.approx(-0.03997, abs=1e-5)
    left = [-x if i % 2 else x for i, x in enumerate(bend)]
    assert dc.bend_curvature(left) == pytest.approx(-1 / r, rel=1e-12)
    # the steering aims at the moved point; beyond the limit on |h4| (0.797 m here) nothing moves
    steered = dc.controls_from_waypoints(bend, gain=0.9, steer_waypoint=2, bend=0.2, bend_limit=1.5)[0]
    h = bend[3] + dc.bend_shift(bend, bend[2], bend[3], 0.2)
    assert steered == pytest.approx(0.9 * math.degrees(math.atan2(h, bend[2])) / 35.0, rel=1e-12)
    assert dc.bend_shift(bend, bend[2], bend[3], 0.2, bend_limit=0.7) == 0.0
    assert dc.controls_from_waypoints(bend, steer_waypoint=2, bend=0.2, bend_limit=0.7) == \
        dc.controls_from_waypoints(bend, steer_waypoint=2)
    # a straight line, or two waypoints at one place: no bend
    assert dc.bend_curvature([2, 0.1, 4, 0.2, 6, 0.3, 8, 0.4]) == pytest.approx(0.0, abs=1e-15)
    assert dc.bend_curvature([2, 0, 2, 0, 6, 1, 8, 2]) == 0.0
    # the same numbers as the C++ client from the same float32 inputs (driving_controller_test.cpp)
    f32 = [float(np.float32(x)) for x in (1.999167, 0.049990, 3.993337, 0.199833, 5.977525, 0.449157, 7.946773, 0.797337)]
    assert dc.bend_shift(f32, f32[2], f32[3], 0.2, 1.5) == -0.039967218370067864
    with pytest.raises(ValueError, match="bend must be 0 ... 1, got 1.5"):
        dc.Controller(bend=1.5)
    with pytest.raises(ValueError, match="bend_limit must be positive, got 0"):
        dc.Controller(bend=0.2, bend_limit=0)


def test_the_controller_holds_the_choices_beyond_the_papers_rule():
    w = [2.0, 0.5, 4.0, 2.0, 6.0, 0.0, 8.0, 1.58]
    assert dc.Controller().controls(w) == dc.controls_from_waypoints(w)  # the defaults are the paper's rule
    c = dc.Controller(steer_waypoint=2, gain=1.2, slowdown=2.0)
    assert c.controls(w, speed=6.0, max_speed=8.0) == dc.controls_from_waypoints(
        w, speed=6.0, max_speed=8.0, gain=1.2, steer_waypoint=2, slowdown=2.0)
    assert c.controls(w)[0] == pytest.approx(1.2 * math.degrees(math.atan(0.5)) / 35.0)
    assert c.settings() == {"steer_waypoint": 2, "steer_gain": 1.2, "slowdown": 2.0, "bend_correction": 0.0,
                            "bend_limit_m": None}
    for bad, message in (({"steer_waypoint": 0}, "steer_waypoint must be 1 ... 4, got 0"),
                         ({"gain": 0.0}, "gain must be positive, got 0.0"),
                         ({"gain": float("nan")}, "gain must be positive, got nan"),
                         ({"slowdown": -0.5}, "slowdown must be >= 0, got -0.5")):
        with pytest.raises(ValueError, match=message):
            dc.Controller(**bad)


def test_the_controllers_options_are_one_list_for_every_command(capsys):
    import argparse
    p = argparse.ArgumentParser(prog="x")
    dc.add_arguments(p, steer_waypoint=2)
    assert dc.from_arguments(p, p.parse_args([])) == dc.Controller(steer_waypoint=2)
    assert dc.from_arguments(p, p.parse_args(["--steer-gain", "1.35", "--turn-slowdown", "1"])) == \
        dc.Controller(2, 1.35, 1.0)
    with pytest.raises(SystemExit) as e:
        dc.from_arguments(p, p.parse_args(["--steer-gain", "-1"]))
    assert e.value.code == 2 and "gain must be positive, got -1.0" in capsys.readouterr().err
    # evaluate refuses it before starting a daemon, with the message
    from sim4cv import driving
    with pytest.raises(SystemExit) as e:
        driving.main(["evaluate", "--policy", "reference", "--out", "/nonexistent/x", "--steer-gain", "0"])
    assert e.value.code == 2 and "gain must be positive, got 0.0" in capsys.readouterr().err


def test_the_steering_may_aim_between_two_waypoints():
    w = [2.0, 0.5, 4.0, 2.0, 6.0, 0.0, 8.0, 0.0]
    # 1.5: halfway between (2, 0.5) and (4, 2), i.e. (3, 1.25)
    assert dc.controls_from_waypoints(w, steer_waypoint=1.5)[0] == pytest.approx(
        math.degrees(math.atan2(1.25, 3.0)) / 35.0)
    assert dc.aim_point(w, 2.0) == (4.0, 2.0) and dc.aim_point(w, 4) == (8.0, 0.0)
    assert dc.aim_point(w, 3.25) == pytest.approx((6.5, 0.0))
    with pytest.raises(ValueError, match="steer_waypoint must be 1 ... 4, got 4.5"):
        dc.Controller(steer_waypoint=4.5)
