"""The active-tracking environment (clients/python/sim4cv/active_tracking.py)
against the real daemon: its API contract, its reward, its episode ends, its
determinism and its daemon's life cycle. About 10 s on a 2-core machine."""

import importlib
import sys
import types

import numpy as np
import pytest

from sim4cv import active_tracking, env_base
from sim4cv.active_tracking import ActiveTrackingEnv


@pytest.fixture(scope="module")
def env():
    e = ActiveTrackingEnv(max_steps=200)
    yield e
    e.close()
    assert e.daemon.proc.returncode == 0


def _run(env, policy, steps, seed):
    rewards, ends = [], 0
    obs, info = env.reset(seed=seed)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(policy(info))
        rewards.append(reward)
        if terminated or truncated:
            ends += 1
            obs, info = env.reset()
    return float(np.mean(rewards)), ends


def test_spaces_and_api_contract(env):
    space = env.observation_space
    assert space.shape == (180, 320, 3) and space.dtype == np.uint8
    assert np.all(space.low == 0) and np.all(space.high == 255)
    action_space = env.action_space
    assert action_space.shape == (3,) and action_space.dtype == np.float32
    assert list(action_space.high) == [8, 8, 90] and list(action_space.low) == [-8, -8, -90]
    action_space.seed(1)
    assert all(action_space.contains(action_space.sample()) for _ in range(20))
    assert not action_space.contains(np.array([9, 0, 0], np.float32))

    obs, info = env.reset(seed=0)
    assert isinstance(obs, np.ndarray) and obs.shape == space.shape and obs.dtype == np.uint8
    assert space.contains(obs) and obs.any()
    for key in ("box", "distance", "angle", "frame_id", "sim_time", "target_distance"):
        assert key in info
    assert info["box"] is not None and info["box"].object_id == env.target_id
    assert info["target_distance"] == pytest.approx(15 / np.tan(np.radians(60)), abs=0.05)  # 15 m up, 60 deg down
    assert abs(info["angle"]) < 45 and abs(info["distance"] - info["target_distance"]) < 5

    frame_id = info["frame_id"]
    for action in ([0, 0, 0], [100, -100, 1000], action_space.sample()):  # out of bounds: clipped
        result = env.step(np.asarray(action, np.float32))
        assert isinstance(result, tuple) and len(result) == 5
        obs, reward, terminated, truncated, info = result
        assert obs.shape == space.shape and obs.dtype == np.uint8
        assert isinstance(reward, float) and -1.0 <= reward <= 1.0
        assert isinstance(terminated, bool) and isinstance(truncated, bool)
        assert info["frame_id"] == frame_id + 1 and info["step"] >= 1
        frame_id = info["frame_id"]
    rgb = env.render()
    assert rgb.shape == (180, 320, 3) and rgb.dtype == np.uint8 and np.array_equal(rgb, obs)


def test_reward_is_the_documented_formula(env):
    obs, info = env.reset(seed=4)
    for _ in range(5):
        obs, reward, terminated, truncated, info = env.step([1.0, 0.5, 10.0])
        expected = (1 - abs(info["distance"] - info["target_distance"]) / info["max_distance"]
                    - abs(info["angle"]) / env.max_angle)
        assert reward == pytest.approx(max(-1.0, min(1.0, expected)))


def test_expert_beats_a_random_agent(env):
    env.action_space.seed(0)
    random_mean, _ = _run(env, lambda info: env.action_space.sample(), 150, seed=1)
    expert_mean, expert_ends = _run(env, env.expert_action, 150, seed=1)
    print("mean reward over 150 steps: random %.3f, expert %.3f" % (random_mean, expert_mean))
    assert expert_ends == 0
    assert expert_mean > 0.85
    assert expert_mean > random_mean + 0.1


def test_flying_away_terminates(env):
    obs, info = env.reset(seed=2)
    for step in range(1, 151):
        obs, reward, terminated, truncated, info = env.step([-8.0, 0.0, 0.0])  # full speed backwards
        if terminated:
            break
    assert terminated and not truncated, info
    assert info["distance"] > info["max_distance"] or info["lost_frames"] >= env.lost_frames
    assert step < 150
    with pytest.raises(active_tracking.ActiveTrackingError):
        env.step([0.0, 0.0, 0.0])  # the episode is over: reset() first


def test_max_steps_truncates():
    with ActiveTrackingEnv(max_steps=5, frame_skip=2, downscale=4) as env:
        obs, info = env.reset(seed=0)
        assert obs.shape == env.observation_space.shape == (45, 80, 3)
        first = info["frame_id"]
        for step in range(5):
            obs, reward, terminated, truncated, info = env.step(env.expert_action(info))
        assert truncated and not terminated and info["frame_id"] == first + 10


def test_same_seed_same_first_observation(env):
    first, info1 = env.reset(seed=7)
    for _ in range(10):
        env.step(env.action_space.sample())
    again, info2 = env.reset(seed=7)
    assert np.array_equal(first, again)
    assert info1["frame_id"] == info2["frame_id"] and info1["start_offset"] == info2["start_offset"]
    assert info1["distance"] == info2["distance"]
    other, info3 = env.reset(seed=8)  # another start offset
    assert info3["start_offset"] != info1["start_offset"] and not np.array_equal(first, other)


def test_close_stops_the_daemon():
    env = ActiveTrackingEnv()
    env.reset(seed=0)
    proc = env.daemon.proc
    assert proc.poll() is None
    env.close()
    assert proc.poll() == 0  # SIGTERM: a clean exit
    env.close()  # twice is fine
    with pytest.raises(active_tracking.ActiveTrackingError):
        env.reset()


def test_a_running_daemon_over_shared_memory(start_transports_daemon):
    daemon = start_transports_daemon()
    with ActiveTrackingEnv(address=daemon.address("shm"), max_steps=30) as env:
        assert env.daemon is None
        obs, info = env.reset(seed=0)
        assert obs.shape == (180, 320, 3)
        rewards = []
        while True:
            obs, reward, terminated, truncated, info = env.step(env.expert_action(info))
            rewards.append(reward)
            if terminated or truncated:
                break
        assert truncated and np.mean(rewards) > 0.7
    assert daemon.proc.poll() is None  # not the env's to stop


def test_uses_gymnasium_when_it_imports(monkeypatch):
    """With gymnasium importable the env is a gymnasium.Env with Box spaces
    (a stand-in module here: gymnasium is not installed on Debian 12)."""
    gym = types.ModuleType("gymnasium")
    spaces = types.ModuleType("gymnasium.spaces")

    class Env:
        pass

    class Box:
        def __init__(self, low, high, shape, dtype):
            self.low, self.high, self.shape, self.dtype = low, high, shape, dtype

    gym.Env, gym.spaces, spaces.Box = Env, spaces, Box
    monkeypatch.setitem(sys.modules, "gymnasium", gym)
    monkeypatch.setitem(sys.modules, "gymnasium.spaces", spaces)
    try:
        base = importlib.reload(env_base)
        module = importlib.reload(active_tracking)
        assert issubclass(module.ActiveTrackingEnv, Env)
        assert isinstance(base.box(0, 255, (2, 2, 3), np.uint8), Box)
    finally:
        monkeypatch.undo()
        importlib.reload(env_base)
        importlib.reload(active_tracking)
