"""The daemon's access token for Hello.token (docs/security.md).

sim4cvd admits a TCP, UDP or WebSocket client only if its Hello carries the
token the daemon wrote at start to a file only the daemon's user can read:
$XDG_RUNTIME_DIR/sim4cv/KIND-PORT.token, or ~/.cache/sim4cv/ without
XDG_RUNTIME_DIR. access_token() finds it the way the C++ client does: the
SIM4CV_TOKEN environment variable if set, else that file for a local address
(a tunnel's local port names no daemon file: set SIM4CV_TOKEN there).
"""

import os

MAX_TOKEN_CHARS = 256
_LOCAL_HOSTS = ("localhost", "::1", "")


def token_folder() -> str:
    """Where the daemon of this user writes its token files."""
    runtime = os.environ.get("XDG_RUNTIME_DIR", "")
    if runtime.startswith("/"):
        return os.path.join(runtime, "sim4cv")
    home = os.environ.get("HOME", "")
    return os.path.join(home if home.startswith("/") else "/tmp", ".cache", "sim4cv")


def is_local(host) -> bool:
    return host is None or host in _LOCAL_HOSTS or str(host).startswith("127.")


def access_token(kind: str, host, port) -> str:
    """The token for the daemon's `kind` ("tcp", "udp") endpoint at
    host:port; "" if neither SIM4CV_TOKEN nor a readable token file has one."""
    given = os.environ.get("SIM4CV_TOKEN", "")
    if given:
        return given
    if not is_local(host) or port is None:
        return ""
    try:
        with open(os.path.join(token_folder(), "%s-%d.token" % (kind, int(port))), "r") as f:
            token = f.readline(MAX_TOKEN_CHARS + 1).strip()
    except OSError:
        return ""
    return token if len(token) <= MAX_TOKEN_CHARS else ""
