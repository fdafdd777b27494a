"""`python:MODULE:FACTORY` trackers, run in a process of their own so that
they get what TraX trackers get: a time limit on every call, after which the
process and everything it started is killed (sim4cv.proctree), and an
error that names the tracker. A tracker whose update() hangs then ends its
own run, not the session.

The object FACTORY() makes has init(image, box) and update(image) ->
(x, y, w, h) or None, and optionally close(). Images travel through a pipe
(a 320 x 180 RGB image is 170 kB).
"""

import multiprocessing
import os

from . import proctree


class PythonTrackerError(RuntimeError):
    """A python: tracker failed: it raised, answered junk, or timed out (then it was killed)."""


def _serve(conn, module, factory):
    """The tracker's process: make the object, then answer (method, args) calls until close or EOF."""
    import importlib
    try:
        made = getattr(importlib.import_module(module), factory)()
        missing = [m for m in ("init", "update") if not callable(getattr(made, m, None))]
        if missing:
            raise ValueError("FACTORY() made %r, which has no %s(...) method" % (made, missing[0]))
    except Exception as e:
        conn.send(("error", "%s: %s" % (type(e).__name__, e)))
        return
    conn.send(("ok", None))
    while True:
        try:
            method, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            if method == "close":
                close = getattr(made, "close", None)
                conn.send(("ok", close() if callable(close) else None))
                return
            conn.send(("ok", getattr(made, method)(*args)))
        except Exception as e:
            conn.send(("error", "%s: %s" % (type(e).__name__, e)))


def check_box(name, answer):
    """(x, y, w, h) floats from an update() answer, None for None; junk is an error naming the tracker."""
    if answer is None:
        return None
    try:
        if isinstance(answer, (str, bytes)) or len(answer) != 4:
            raise TypeError
        box = tuple(float(v) for v in answer)
    except (TypeError, ValueError):
        raise PythonTrackerError("%s: update() answered %.200r; expected (x, y, w, h) or None" % (name, answer))
    return box  # NaN: no estimate; inf or far outside: the daemon refuses it and the session counts it


class TrackerProcess:
    """One python: tracker in its own process; every call waits at most `timeout` seconds."""

    def __init__(self, module, factory, timeout=30.0):
        self.name = "python:%s:%s" % (module, factory)
        self.timeout = float(timeout)
        context = multiprocessing.get_context("spawn")
        self._conn, child = context.Pipe()
        self._token = proctree.new_token()
        saved = os.environ.get(proctree.TOKEN_VARIABLE)
        os.environ[proctree.TOKEN_VARIABLE] = self._token  # inherited by the process and all it starts
        try:
            self._proc = context.Process(target=_serve, args=(child, module, factory), name=self.name)
            self._proc.start()
        finally:
            if saved is None:
                os.environ.pop(proctree.TOKEN_VARIABLE, None)
            else:
                os.environ[proctree.TOKEN_VARIABLE] = saved
        child.close()
        self._closed = False
        try:
            self._answer("start")
        except PythonTrackerError as e:
            raise ValueError(str(e)) from None  # what make_tracker raised before: a bad specification

    def call(self, method, *args):
        if self._closed:
            raise PythonTrackerError("%s is closed" % self.name)
        try:
            self._conn.send((method, args))
        except (OSError, ValueError) as e:
            self._kill()
            raise PythonTrackerError("%s: its process is gone (%s)" % (self.name, e)) from None
        return self._answer(method)

    def _answer(self, method):
        what = "starting" if method == "start" else "%s()" % method
        try:
            ready = self._conn.poll(self.timeout)
        except (OSError, EOFError):
            ready = True
        if not ready:
            self._kill()
            raise PythonTrackerError("%s: %s did not answer within %.3g s; killed it" % (self.name, what, self.timeout))
        try:
            status, value = self._conn.recv()
        except (EOFError, OSError):
            self._kill()
            raise PythonTrackerError("%s: its process ended during %s (exit code %s)"
                                     % (self.name, what, self._proc.exitcode)) from None
        if status == "error":
            if method in ("start", "close"):
                self._kill()
            raise PythonTrackerError("%s: %s raised %s" % (self.name, what, value))
        return value

    def close(self):
        if self._closed:
            return
        try:
            self.call("close")
        except PythonTrackerError:
            pass
        self._kill()

    def _kill(self):
        self._closed = True
        if self._proc.is_alive():
            proctree.kill_tree(self._proc.pid, self._token)
        self._proc.join(5.0)
        self._conn.close()
