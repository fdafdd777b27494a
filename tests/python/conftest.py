"""Fixtures of the Python client's integration tests: the real sim4cvd binary.

The daemon is taken from $SIM4CVD (default: build/server/daemon/sim4cvd under
the repository root) and started as
    sim4cvd --tcp-port 0 --mode lockstep [extra flags]
once per test. Each test ends by sending SIGTERM and asserting exit status 0.
If the binary is missing the tests fail (they do not skip).
"""

import itertools
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

import sim4cv  # noqa: E402

LISTENING = re.compile(r"^sim4cvd listening tcp=(\d+)(\s|$)")
_SHM_NAMES = itertools.count(1)


def unique_shm_name():
    """A --shm-name no other test (or test run) uses: /sim4cv-pytest-<pid>-<n>."""
    return "/sim4cv-pytest-%d-%d" % (os.getpid(), next(_SHM_NAMES))
STARTUP_TIMEOUT_S = 60.0
EXIT_TIMEOUT_S = 20.0


def daemon_path():
    path = os.environ.get("SIM4CVD", "build/server/daemon/sim4cvd")
    if not os.path.isabs(path) and not os.path.exists(path):
        path = os.path.join(REPO_ROOT, path)
    return os.path.abspath(path)


class Daemon:
    """A running sim4cvd; stdout is drained by a thread, stderr goes to a file."""

    def __init__(self, args, log_dir):
        path = daemon_path()
        if not os.access(path, os.X_OK):
            pytest.fail("sim4cvd binary not found or not executable at %s "
                        "(build it, or set SIM4CVD to its path)" % path, pytrace=False)
        self.args = [path, "--tcp-port", "0", "--mode", "lockstep"] + list(args)
        self.stderr_path = os.path.join(str(log_dir), "sim4cvd-%d.stderr" % id(self))
        self._stderr = open(self.stderr_path, "wb")
        self.proc = subprocess.Popen(self.args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=self._stderr)
        self.stdout_lines = []
        self._lines = queue.Queue()
        self._reader = threading.Thread(target=self._drain_stdout, daemon=True)
        self._reader.start()
        self.port = self._wait_listening()

    # The listening line's fields: tcp=PORT [udp=PORT] [shm=NAME] (docs/protocol.md 1).
    @property
    def fields(self):
        return dict(item.split("=", 1) for item in self.stdout_lines[0].split()[2:] if "=" in item)

    @property
    def udp_port(self):
        return int(self.fields["udp"]) if "udp" in self.fields else None

    @property
    def shm_name(self):
        return self.fields.get("shm")

    def address(self, transport):
        """"tcp://127.0.0.1:PORT", "udp://127.0.0.1:PORT" or "shm://NAME" of this daemon."""
        if transport == "shm":
            return "shm://" + self.shm_name
        return "%s://127.0.0.1:%d" % (transport, self.port if transport == "tcp" else self.udp_port)

    def _drain_stdout(self):
        # Keep reading so the daemon never blocks on a full pipe.
        for raw in self.proc.stdout:
            line = raw.decode("utf-8", "replace").rstrip("\n")
            self.stdout_lines.append(line)
            self._lines.put(line)
        self._lines.put(None)

    def log(self):
        if not self._stderr.closed:
            self._stderr.flush()
        with open(self.stderr_path, "rb") as f:
            err = f.read().decode("utf-8", "replace")
        return "command: %s\nstdout:\n%s\nstderr (last 4000 chars):\n%s" % (
            " ".join(self.args), "\n".join(self.stdout_lines), err[-4000:])

    def _wait_listening(self):
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while True:
            try:
                line = self._lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                self.kill()
                pytest.fail("sim4cvd printed no 'sim4cvd listening tcp=PORT' line within %.0f s\n%s"
                            % (STARTUP_TIMEOUT_S, self.log()), pytrace=False)
            if line is None:
                rc = self.proc.wait()
                pytest.fail("sim4cvd exited with status %s before listening\n%s" % (rc, self.log()),
                            pytrace=False)
            match = LISTENING.match(line)
            if match:
                if len(self.stdout_lines) != 1:
                    self.kill()
                    pytest.fail("the listening line was not sim4cvd's first stdout line\n%s" % self.log(),
                                pytrace=False)
                return int(match.group(1))

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()

    def terminate(self):
        """SIGTERM, then the exit status (killing it if it does not exit)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.kill()
            return "no exit within %.0f s of SIGTERM" % EXIT_TIMEOUT_S
        finally:
            self._reader.join(5)
            self._stderr.close()


@pytest.fixture
def start_daemon(tmp_path):
    """Factory: start_daemon(*extra_flags) -> Daemon. All are SIGTERMed at the
    end of the test and must exit with status 0."""
    daemons, clients = [], []

    def start(*extra):
        d = Daemon(extra, tmp_path)
        daemons.append(d)
        return d

    start.clients = clients
    yield start
    for c in clients:
        c.close()
    failures = []
    for d in daemons:
        rc = d.terminate()
        if rc != 0:
            failures.append("sim4cvd exit status after SIGTERM: %r (expected 0)\n%s" % (rc, d.log()))
    if failures:
        pytest.fail("\n\n".join(failures), pytrace=False)


@pytest.fixture
def start_transports_daemon(start_daemon):
    """Factory: a daemon serving TCP, UDP and a fresh shared-memory ring
    (extra flags appended, so they may override these)."""

    def start(*extra):
        return start_daemon("--udp-port", "0", "--shm-name", unique_shm_name(), *extra)

    return start


@pytest.fixture
def daemon(start_daemon):
    return start_daemon()


@pytest.fixture
def connect(daemon, start_daemon):
    """connect(name="...", **kwargs) -> a handshaken Client (of the default
    daemon unless target= is given); its Welcome is client.welcome."""

    def make(name="pytest", target=None, **kwargs):
        client = sim4cv.Client()
        start_daemon.clients.append(client)
        client.connect("127.0.0.1", (target or daemon).port, name, **kwargs)
        return client

    return make
