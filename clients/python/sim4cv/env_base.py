"""What sim4cv's Gymnasium-style environments (sim4cv.active_tracking,
sim4cv.driving_env) share: their spaces, gymnasium's when gymnasium is
importable and small stand-ins with the same methods when not (Debian has no
gymnasium), and their base class SimEnv (gymnasium.Env or object) with the
session's end: close(), a context manager, close on garbage collection."""

from typing import Dict

import numpy as np


try:  # pragma: no cover - depends on the host
    import gymnasium as _gym
    from gymnasium import spaces as _spaces
except ImportError:
    _gym = None
    _spaces = None


# ----------------------------------------------------------------------------- spaces without gymnasium

class Box:
    """A stand-in for gymnasium.spaces.Box when gymnasium is not installed:
    shape, dtype, low, high (arrays of that shape), sample(), contains(x),
    seed(s)."""

    def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
        self.dtype = np.dtype(dtype)
        if shape is None:
            shape = np.shape(low)
        self.shape = tuple(int(n) for n in shape)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)
        return [seed]

    def sample(self):
        if np.issubdtype(self.dtype, np.integer):
            return self._rng.integers(self.low, self.high, size=self.shape, endpoint=True, dtype=self.dtype)
        return self._rng.uniform(self.low, self.high, size=self.shape).astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        if x.shape != self.shape:
            return False
        if np.issubdtype(self.dtype, np.integer) and not np.issubdtype(x.dtype, np.integer):
            return False
        return bool(np.all(x >= self.low) and np.all(x <= self.high))

    def __contains__(self, x):
        return self.contains(x)

    def __repr__(self):
        return "Box(%s, %s, %s, %s)" % (self.low.min(), self.high.max(), self.shape, self.dtype)


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


def box(low, high, shape, dtype):
    if _spaces is not None:
        return _spaces.Box(low=low, high=high, shape=shape, dtype=dtype)
    return Box(low, high, shape, dtype)


def dict_space(spaces):
    return _spaces.Dict(spaces) if _spaces is not None else DictSpace(spaces)


class _PlainEnv:
    """What the environments need of gymnasium.Env when gymnasium is absent:
    metadata, render_mode, spec, np_random (numpy's default_rng(seed), the
    generator gymnasium makes from the same seed), reset(seed) reseeding it,
    unwrapped."""

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


class SimEnv(_gym.Env if _gym is not None else _PlainEnv):
    """The base of sim4cv's environments: a subclass sets self.client (its
    session), self.daemon (the daemon it started, or None) and
    self._closed = False once they exist."""

    client = None
    daemon = None
    _closed = True  # until the subclass has a session to end

    def close(self):
        """Ends the session and stops the env's own daemon (if it started one). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        self._done = True
        if self.client is not None:
            try:
                self.client.close()
            except Exception:  # noqa: BLE001 (a session that already broke)
                pass
            self.client = None
        if self.daemon is not None:
            self.daemon.stop()  # kept: its exit status stays readable (daemon.proc.returncode)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001
            pass
