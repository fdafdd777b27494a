"""Transport addresses: "tcp://HOST:PORT", "udp://HOST:PORT", "shm://NAME"."""

import re
from typing import NamedTuple, Optional

ACCEPTED_FORMS = ("tcp://HOST:PORT, udp://HOST:PORT (HOST a name, an IPv4 address or [IPv6]) "
                  "or shm://NAME (NAME as given to sim4cvd --shm-name, e.g. shm:///sim4cv-demo)")
SHM_MAX_NAME_CHARS = 96  # --shm-name: 1-96 characters, no '/' after the first

_HOST_PORT = re.compile(r"^(?:\[(?P<v6>[0-9A-Fa-f:.]+)\]|(?P<host>[^:/\[\]\s]+)):(?P<port>\d{1,5})$")


class Address(NamedTuple):
    """A parsed address. transport: "tcp", "udp" or "shm"; host/port for
    tcp and udp; name ("/NAME", with its slash) for shm."""
    transport: str
    host: Optional[str] = None
    port: Optional[int] = None
    name: Optional[str] = None

    def __str__(self):
        if self.transport == "shm":
            return "shm://" + self.name
        host = "[%s]" % self.host if ":" in self.host else self.host
        return "%s://%s:%d" % (self.transport, host, self.port)


def _bad(address, why):
    return ValueError("bad sim4cv address %r: %s; expected %s" % (address, why, ACCEPTED_FORMS))


def parse_address(address: str) -> Address:
    """Parses an address string; raises ValueError naming the address and
    the accepted forms if it is not one of them."""
    if not isinstance(address, str):
        raise _bad(address, "not a string")
    scheme, sep, rest = address.partition("://")
    scheme = scheme.lower()
    if not sep or scheme not in ("tcp", "udp", "shm"):
        raise _bad(address, "unknown or missing transport %r" % scheme if sep else "no transport:// prefix")
    if scheme == "shm":
        name = rest if rest.startswith("/") else "/" + rest
        if len(name) < 2 or len(name) > SHM_MAX_NAME_CHARS + 1 or "/" in name[1:] or "\0" in name:
            raise _bad(address, "the shared-memory name must be 1-%d characters with no '/' after the first"
                       % SHM_MAX_NAME_CHARS)
        return Address("shm", name=name)
    match = _HOST_PORT.match(rest)
    if not match:
        raise _bad(address, "expected HOST:PORT after %s://" % scheme)
    port = int(match.group("port"))
    if not 1 <= port <= 65535:
        raise _bad(address, "port %d is not in 1-65535" % port)
    return Address(scheme, match.group("v6") or match.group("host"), port)
