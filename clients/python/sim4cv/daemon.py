"""Starting sim4cvd from Python: for tools that run their own daemon
(sequence generation, tracking sessions, experiments, the active-tracking
environment) and for tests.

    with OwnDaemon(["--map", "scenes/tracking/hard_urban.map"], mode="realtime") as d:
        client = sim4cv.connect(d.address)        # tcp://127.0.0.1:PORT
        d.fields["udp"], d.fields.get("shm")      # every field of the listening line

The binary is $SIM4CVD; else, in the source tree, its build/server/daemon/sim4cvd; else an
installed one: sim4cvd on PATH, or in this Python's prefix (a venv's bin/), /usr/local or /usr.
"""

import os
import queue
import shutil
import subprocess
import sys
import threading
import time
from typing import Dict, List, Optional, Sequence

SOURCE_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
IN_SOURCE_TREE = os.path.isfile(os.path.join(SOURCE_ROOT, "protocol", "sim4cv.proto"))
LISTENING_PREFIX = "sim4cvd listening "


class DaemonError(RuntimeError):
    """sim4cvd could not be found or started; the message says why (its
    command line and the end of its stderr)."""


def installed_program(name: str) -> Optional[str]:
    """An installed sim4cv program (the .deb, cmake --install): on PATH, or in bin/ of this
    Python's prefix, /usr/local or /usr; None if there is none."""
    found = shutil.which(name)
    if found:
        return os.path.abspath(found)
    for prefix in (sys.prefix, "/usr/local", "/usr"):
        candidate = os.path.join(prefix, "bin", name)
        if os.access(candidate, os.X_OK):
            return candidate
    return None


def installed_daemon() -> Optional[str]:
    """An installed sim4cvd; None if there is none."""
    return installed_program("sim4cvd")


def daemon_path() -> str:
    path = os.environ.get("SIM4CVD")
    if path is None and not IN_SOURCE_TREE:
        path = installed_daemon()
        if path is None:
            raise DaemonError("sim4cvd not found on PATH nor in %s/bin, /usr/local/bin, /usr/bin: install sim4cv "
                              "(apt install ./sim4cv_*.deb, or cmake --install) or set SIM4CVD" % sys.prefix)
    path = path or "build/server/daemon/sim4cvd"
    if not os.path.isabs(path) and not os.path.exists(path):
        path = os.path.join(SOURCE_ROOT, path)
    return os.path.abspath(path)


def data_root() -> str:
    """Where scenes/ and models/ are: the source tree, or an installed daemon's
    PREFIX/share/sim4cv (the source tree's when neither has them)."""
    if not IN_SOURCE_TREE:
        daemon = os.environ.get("SIM4CVD") or installed_daemon()
        if daemon:
            share = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(daemon))), "share", "sim4cv")
            if os.path.isdir(os.path.join(share, "scenes")):
                return share
    return SOURCE_ROOT


# The folder the tools find scenes/ and models/ in (data_root(), at import).
REPO_ROOT = data_root()


def parse_listening_line(line: str) -> Optional[Dict[str, str]]:
    """The key=value fields of a listening line (docs/protocol.md 1), or None."""
    if not line.startswith(LISTENING_PREFIX):
        return None
    return dict(field.split("=", 1) for field in line[len(LISTENING_PREFIX):].split() if "=" in field)


def die_with_parent(signal_number: int = 9) -> None:
    """In the forked child before exec: `signal_number` when the thread that started
    it dies, so a task killed with kill -9 (a scheduler's timeout) leaves no
    daemon behind (Linux prctl PR_SET_PDEATHSIG; elsewhere nothing)."""
    import ctypes
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal_number, 0, 0, 0)  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class OwnDaemon:
    """A sim4cvd of our own: --tcp-port 0 and --mode `mode` plus `args`;
    stdout and stderr are drained by threads (the daemon never blocks on a
    pipe), the last 200 stderr lines kept for error messages."""

    def __init__(self, args: Sequence[str] = (), mode: str = "lockstep", wait_binary_s: float = 60.0,
                 startup_s: float = 60.0):
        path = daemon_path()
        deadline = time.monotonic() + wait_binary_s
        while not os.access(path, os.X_OK):  # a rebuild may be replacing it
            if time.monotonic() > deadline:
                raise DaemonError("sim4cvd not found or not executable at %s (set SIM4CVD)" % path)
            time.sleep(1.0)
        self.args: List[str] = [path, "--tcp-port", "0", "--mode", mode] + list(args)
        self.proc = subprocess.Popen(self.args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, preexec_fn=die_with_parent)
        self._lines: "queue.Queue[Optional[str]]" = queue.Queue()
        self.stderr_tail: List[str] = []
        threading.Thread(target=self._drain, args=(self.proc.stdout, True), daemon=True).start()
        threading.Thread(target=self._drain, args=(self.proc.stderr, False), daemon=True).start()
        deadline = time.monotonic() + startup_s
        while True:
            try:
                line = self._lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                self.stop()
                raise DaemonError("sim4cvd printed no listening line within %.0f s: %s"
                                  % (startup_s, " ".join(self.args))) from None
            if line is None:
                rc = self.proc.wait()
                time.sleep(0.1)  # the stderr thread's last lines
                raise DaemonError("sim4cvd exited with status %s before listening: %s\n%s"
                                  % (rc, " ".join(self.args), "\n".join(self.stderr_tail[-20:])))
            fields = parse_listening_line(line)
            if fields is not None:
                self.fields = fields
                self.port = int(fields["tcp"])
                self.address = "tcp://127.0.0.1:%d" % self.port
                return

    def _drain(self, stream, is_stdout):
        for raw in stream:
            line = raw.decode("utf-8", "replace").rstrip("\n")
            if is_stdout:
                self._lines.put(line)
            else:
                self.stderr_tail.append(line)
                del self.stderr_tail[:-200]
        if is_stdout:
            self._lines.put(None)

    def running(self) -> bool:
        return self.proc.poll() is None

    def stop(self) -> Optional[int]:
        """SIGTERM, then SIGKILL after 20 s; the exit status."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode

    def __enter__(self) -> "OwnDaemon":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
