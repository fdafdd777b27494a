"""The Gymnasium-style driving environment (sim4cv.driving_env) with a real
sim4cvd: observations of the camera's size, the reference controller earning
a positive reward, full lock ending in a lane departure, seeded resets that
repeat exactly (start, first image, randomised conditions), refused NaN
actions, truncation, and the gymnasium code path (a stand-in module)."""

import importlib
import math
import os
import sys
import types

import numpy as np
import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import driving_env as de  # noqa: E402
from sim4cv import env_base as des  # noqa: E402
from sim4cv import driving_metrics as dm  # noqa: E402

DESERT = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_desert.map")
URBAN = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")
CAMERA = {"width": 160, "height": 96}


@pytest.fixture(scope="module")
def env():
    with de.DrivingEnv(maps=[DESERT], camera=CAMERA) as e:
        yield e


def test_spaces_and_bad_settings_without_a_daemon():
    e = de.DrivingEnv(maps=[DESERT], camera=CAMERA, channels=("rgb", "depth", "semantic", "boxes"))
    assert e.daemon is None  # started by reset
    assert set(e.observation_space.spaces) == {"rgb", "depth", "semantic"}
    assert e.observation_space["rgb"].shape == (96, 160, 3) and e.observation_space["rgb"].dtype == np.uint8
    assert e.observation_space["depth"].shape == (96, 160) and e.observation_space["depth"].dtype == np.float32
    assert e.action_space.shape == (3,)
    assert list(e.action_space.low) == [-1, 0, 0] and list(e.action_space.high) == [1, 1, 1]
    assert e.action_space.contains(e.action_space.sample())
    with pytest.raises(de.DrivingEnvError, match="call reset"):
        e.step([0, 0, 0])
    e.close()
    with pytest.raises(ValueError, match="unknown channel 'colour'"):
        de.DrivingEnv(maps=[DESERT], channels=("colour",))
    with pytest.raises(ValueError, match="unknown camera setting.*zoom"):
        de.DrivingEnv(maps=[DESERT], camera={"zoom": 2})
    with pytest.raises(ValueError, match="unknown conditions preset 'snow'"):
        de.DrivingEnv(maps=[DESERT], conditions="snow")
    with pytest.raises(de.DrivingEnvError, match="neither train, val, test, extra nor a map file"):
        de.DrivingEnv(maps=["nowhere.map"])


def test_reset_returns_an_rgb_observation_of_the_camera_size(env):
    obs, info = env.reset(seed=1)
    assert set(obs) == {"rgb"}
    assert obs["rgb"].shape == (96, 160, 3) and obs["rgb"].dtype == np.uint8
    assert obs["rgb"].flags.writeable and obs["rgb"].std() > 1.0  # a copy, and a real image
    assert env.observation_space.contains(obs)
    assert abs(info["deviation_m"]) < 0.05 and info["speed"] < 0.1 and info["sim_time"] == 0.0
    assert info["map"] == "driving_test_01_desert" and info["route"] == "loop"
    assert info["u"] == pytest.approx(info["u0"], abs=0.01) and info["collisions"] == 0
    assert info["lane_departure"] is False and info["conditions"]["preset"] == "clear_noon"
    np.testing.assert_array_equal(env.render(), obs["rgb"])


def test_the_reference_controller_earns_a_positive_reward_without_termination(env):
    env.reset(seed=2)
    total, deviations = 0.0, []
    for _ in range(150):
        obs, reward, terminated, truncated, info = env.step(env.reference_action())
        assert not terminated and not truncated
        total += reward
        deviations.append(abs(info["deviation_m"]))
    assert total > 10.0  # metres of progress, less the small deviation term
    assert info["progress_m"] > 10.0 and info["speed"] > 3.0
    assert max(deviations) < 0.5 and info["collisions"] == 0
    assert info["sim_time"] == pytest.approx(150 / 30.0, abs=1e-3)
    # the reward is exactly progress minus the weighted deviation over the step
    before = info["u"]
    _, reward, _, _, info = env.step(env.reference_action())
    assert reward == pytest.approx(info["u"] - before - 2.0 * abs(info["deviation_m"]) / 30.0, abs=1e-9)


def test_full_lock_ends_in_a_lane_departure_with_a_negative_reward(env):
    env.reset(seed=3)
    for i in range(300):
        _, reward, terminated, truncated, info = env.step([1.0, 0.6, 0.0])
        if terminated or truncated:
            break
    assert terminated and not truncated, info
    assert info["reason"] == "lane_departure" and info["lane_departure"]
    assert abs(info["deviation_m"]) > dm.LANE_DEPARTURE_M
    assert reward < -5.0  # the terminal penalty (10) dominates one step's progress
    with pytest.raises(de.DrivingEnvError, match="call reset"):
        env.step([0, 0, 0])


def test_the_same_seed_gives_the_same_start_and_image():
    with de.DrivingEnv(maps=[DESERT, URBAN], camera=CAMERA) as e:
        starts = []
        for seed in (7, 8, 7):
            obs, info = e.reset(seed=seed)
            starts.append(((info["map"], info["route"], info["u0"]), obs["rgb"]))
            e.step([0.0, 1.0, 0.0])  # the episode moves on before the next reset
        assert starts[0][0] == starts[2][0]
        np.testing.assert_array_equal(starts[0][1], starts[2][1])
        assert starts[1][0] != starts[0][0]
        obs, info = e.reset(seed=7, options={"u": 25.0, "map": 0})
        assert info["u0"] == 25.0 and info["map"] == "driving_test_01_desert"


def test_nan_actions_are_refused_naming_them_and_the_rest_is_clipped(env):
    env.reset(seed=4)
    with pytest.raises(ValueError, match="steering is NaN"):
        env.step([math.nan, 0.5, 0.0])
    with pytest.raises(ValueError, match="brake is NaN"):
        env.step(np.array([0.0, 0.5, np.nan], dtype=np.float32))
    with pytest.raises(ValueError, match="3 numbers"):
        env.step([0.0, 0.5])
    _, _, _, _, info = env.step([-math.inf, 3.0, -1.0])  # the episode is still on
    assert (info["steering"], info["throttle"], info["brake"]) == (-1.0, 1.0, 0.0)


def test_truncation_after_max_seconds():
    with de.DrivingEnv(maps=[DESERT], camera=CAMERA, max_seconds=1.0, frame_hz=15) as e:
        e.reset(seed=5)
        for i in range(15):
            _, _, terminated, truncated, info = e.step([0.0, 0.3, 0.0])
            assert not terminated
            assert truncated == (i == 14)
        assert info["reason"] == "time_limit" and info["sim_time"] == pytest.approx(1.0)
        daemon = e.daemon
    assert daemon.proc.returncode == 0  # close() stopped it cleanly


@pytest.mark.parametrize("mode", [True, "daemon"])
def test_randomize_picks_the_same_conditions_for_the_same_seed(mode):
    with de.DrivingEnv(maps=[DESERT], camera=CAMERA, randomize=mode) as e:
        conditions, images = [], []
        for seed in (11, 12, 13, 11):
            obs, info = e.reset(seed=seed)
            conditions.append(info["conditions"])
            images.append(obs["rgb"])
        assert conditions[0] == conditions[3]
        np.testing.assert_array_equal(images[0], images[3])
        assert len({(c["preset"], c["hour"]) for c in conditions[:3]}) > 1
        if mode is True:
            assert all(c["preset"] in de.PRESETS and c["exposure"] == 1.0 for c in conditions)
        # an episode's own preset, then back to the draws
        _, info = e.reset(seed=11, options={"conditions": "night"})
        assert (info["conditions"]["preset"], info["conditions"]["hour"]) == ("night", 23.0)
        _, info = e.reset(seed=11)
        assert info["conditions"] == conditions[0]


def test_the_gymnasium_code_path_with_a_stand_in_module(monkeypatch):
    gym = types.ModuleType("gymnasium")
    spaces = types.ModuleType("gymnasium.spaces")

    class Env:
        _np_random = None

        @property
        def np_random(self):
            if self._np_random is None:
                self._np_random = np.random.default_rng()
            return self._np_random

        def reset(self, *, seed=None, options=None):
            if seed is not None:
                self._np_random = np.random.default_rng(seed)

    class Box:
        def __init__(self, low, high, shape, dtype):
            self.low, self.high, self.shape, self.dtype = low, high, shape, np.dtype(dtype)

    class Dict:
        def __init__(self, d):
            self.spaces = d

    gym.Env, spaces.Box, spaces.Dict, gym.spaces = Env, Box, Dict, spaces
    monkeypatch.setitem(sys.modules, "gymnasium", gym)
    monkeypatch.setitem(sys.modules, "gymnasium.spaces", spaces)
    try:
        importlib.reload(des)
        module = importlib.reload(de)
        e = module.DrivingEnv(maps=[DESERT], camera=CAMERA)
        assert isinstance(e, Env) and isinstance(e.action_space, Box)
        assert isinstance(e.observation_space, Dict) and e.observation_space.spaces["rgb"].shape == (96, 160, 3)
        e.close()
    finally:
        monkeypatch.undo()
        importlib.reload(des)
        importlib.reload(de)
    assert des._gym is None or des._gym.__name__ == "gymnasium"
