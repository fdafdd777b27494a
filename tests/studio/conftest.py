"""Fixtures of the studio's tests: real sim4cvd processes with --http-port
(clients/python/sim4cv/daemon.py's OwnDaemon; $SIM4CVD or the build tree's
binary), and for the browser tests Debian's Chromium driven through our own
DevTools driver (tools/cdp_driver.py).

With STUDIO_SKIP_EXIT set (the studio_browser CTest entry sets 77), a run
whose tests were all skipped because Chromium is missing exits with that
status, so CTest reports the test as skipped instead of passed."""

import contextlib
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))
sys.path.insert(0, os.path.join(REPO_ROOT, "tools"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from sim4cv.access import access_token  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402

MAP = os.path.join(REPO_ROOT, "scenes", "tracking", "easy_urban.map")
TIMEOUT_S = 30.0  # generous: a loaded 2-core machine runs real-time daemons slower


@contextlib.contextmanager
def clean_page(browser, url, ready):
    """A tab on `url`, once the JavaScript expression `ready` holds. On leaving
    it must have logged no exception, no console error and no warning (the
    MujocoTest rule: a warning is a failure)."""
    page = browser.new_page(url)
    page.wait_for(ready, TIMEOUT_S)
    yield page
    page.collect()
    assert page.problems == [], page.problems
    assert [text for kind, text in page.console if kind in ("warning", "error")] == []


def start_daemon(*args, mode="lockstep"):
    """A sim4cvd with the studio on a free port; .fields["http"] is the port."""
    daemon = OwnDaemon(["--http-port", "0", "--udp-port", "-1"] + list(args), mode=mode)
    daemon.http = int(daemon.fields["http"])
    # The access token the daemon wrote for its HTTP port (docs/security.md): the page's ?token=.
    daemon.token = access_token("http", "127.0.0.1", daemon.http)
    return daemon


@pytest.fixture
def studio_daemon():
    """Each test's own daemon factory; every daemon must exit with status 0."""
    started = []

    def start(*args, mode="lockstep"):
        daemon = start_daemon(*args, mode=mode)
        started.append(daemon)
        return daemon

    yield start
    for daemon in started:
        status = daemon.stop()
        assert status == 0, "sim4cvd exited with %s:\n%s" % (status, "\n".join(daemon.stderr_tail[-30:]))


def pytest_sessionfinish(session, exitstatus):
    skip_exit = os.environ.get("STUDIO_SKIP_EXIT")
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if not skip_exit or reporter is None or exitstatus != 0:
        return
    skipped = len(reporter.stats.get("skipped", []))
    passed = len(reporter.stats.get("passed", []))
    if skipped and not passed:
        session.exitstatus = int(skip_exit)
