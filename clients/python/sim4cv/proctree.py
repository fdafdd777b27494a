"""Killing a tracker process and everything it started, including children
that left its process group with setsid() (a daemonising helper, a server
it forked). cgroups are not available to us, so descendants are found in
/proc: by parent links from the tracker's pid, and by a marker variable in
their environment (SIM4CV_TRACKER_TOKEN), which survives setsid() and the
death of the parent that would break the parent links.

    token = new_token(); env = dict(os.environ, **marker(token))
    proc = subprocess.Popen(..., env=env, start_new_session=True)
    ...
    kill_tree(proc.pid, token)
"""

import os
import signal
import uuid

TOKEN_VARIABLE = "SIM4CV_TRACKER_TOKEN"


def new_token():
    return uuid.uuid4().hex


def marker(token):
    return {TOKEN_VARIABLE: token}


def _pids():
    try:
        return [int(name) for name in os.listdir("/proc") if name.isdigit()]
    except OSError:
        return []


def _parent(pid):
    try:
        with open("/proc/%d/stat" % pid, "rb") as f:
            stat = f.read()
        return int(stat[stat.rindex(b")") + 2:].split()[1])  # the command may hold spaces and parentheses
    except (OSError, ValueError, IndexError):
        return None


def environments():
    """(pid, its environment as a list of b"NAME=VALUE") for every process whose
    environment this one may read (others' and vanished ones are left out)."""
    for pid in _pids():
        try:
            with open("/proc/%d/environ" % pid, "rb") as f:
                yield pid, f.read().split(b"\0")
        except OSError:  # gone, or not ours to read
            continue


def descendants(root, token=None):
    """Pids below `root` by parent links, and every process whose environment holds the token."""
    pids = _pids()
    children = {}
    for pid in pids:
        parent = _parent(pid)
        if parent is not None:
            children.setdefault(parent, []).append(pid)
    found, todo = set(), [root]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    if token:
        needle = ("%s=%s" % (TOKEN_VARIABLE, token)).encode()
        me = os.getpid()
        found.update(pid for pid, environment in environments() if pid not in (me, root) and needle in environment)
    found.discard(root)
    return found


def kill_tree(pid, token=None):
    """SIGKILL to `pid`, its process group (if it leads one: start_new_session),
    its descendants and every process carrying `token`; the caller reaps `pid`."""
    others = descendants(pid, token)
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass  # not a group leader (a multiprocessing child): killed with the others below
    for other in sorted(others) + [pid]:
        try:
            os.kill(other, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
