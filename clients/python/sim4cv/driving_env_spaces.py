"""The spaces and base class of sim4cv.driving_env: gymnasium's when
gymnasium is importable, small stand-ins with the same methods when not
(Debian has no gymnasium), so the environment is the same code either way."""

from typing import Dict

import numpy as np

from .active_tracking import Box

try:  # pragma: no cover - depends on the host
    import gymnasium as _gym
    from gymnasium import spaces as _spaces
except ImportError:
    _gym = None
    _spaces = None


# ----------------------------------------------------------------------------- spaces without gymnasium

class DictSpace:
    """A stand-in for gymnasium.spaces.Dict: .spaces (name -> Box),
    sample(), contains(x), seed(s), [name]."""

    def __init__(self, spaces: Dict[str, Box]):
        self.spaces = dict(spaces)

    def __getitem__(self, key):
        return self.spaces[key]

    def keys(self):
        return self.spaces.keys()

    def seed(self, seed=None):
        for i, s in enumerate(self.spaces.values()):
            s.seed(None if seed is None else seed + i)
        return [seed]

    def sample(self):
        return {k: s.sample() for k, s in self.spaces.items()}

    def contains(self, x):
        return isinstance(x, dict) and set(x) == set(self.spaces) and all(
            self.spaces[k].contains(v) for k, v in x.items())

    def __contains__(self, x):
        return self.contains(x)

    def __repr__(self):
        return "Dict(%s)" % ", ".join("%r: %r" % kv for kv in self.spaces.items())


def _box(low, high, shape, dtype):
    if _spaces is not None:
        return _spaces.Box(low=low, high=high, shape=shape, dtype=dtype)
    return Box(low, high, shape, dtype)


def _dict(spaces):
    return _spaces.Dict(spaces) if _spaces is not None else DictSpace(spaces)


class _PlainEnv:
    """What DrivingEnv needs of gymnasium.Env when gymnasium is absent:
    metadata, render_mode, spec, np_random (numpy's default_rng(seed), the
    generator gymnasium makes from the same seed), reset(seed) reseeding it,
    close(), unwrapped, the context manager."""

    metadata: dict = {}
    render_mode = None
    spec = None
    _np_random = None

    @property
    def np_random(self) -> np.random.Generator:
        if self._np_random is None:
            self._np_random = np.random.default_rng()
        return self._np_random

    @property
    def unwrapped(self):
        return self

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            self._np_random = np.random.default_rng(seed)

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


_EnvBase = _gym.Env if _gym is not None else _PlainEnv
