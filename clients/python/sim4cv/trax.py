"""Drive any VOT tracker through the TraX protocol.

    from sim4cv.trax import TraxTracker
    with TraxTracker("/usr/bin/python3 clients/python/examples/trax_ncc_tracker.py") as t:
        t.init(rgb0, (x, y, w, h))        # HxWx3 uint8 RGB, box in pixels
        box = t.update(rgb1)              # (x, y, w, h), or None if the tracker gives no box
        print(t.name, t.elapsed)

sim4cv is the TraX *client*: it starts the tracker process (the TraX
*server*) and talks to it over the process's standard input and output, or
over a TCP socket (transport="socket": the tracker connects to the port in
TRAX_SOCKET). Message parsing and image encoding are in
sim4cv.trax_protocol. Every failure is a TraxError, after which the process
(its whole process group) is gone. See docs/trax.md.
"""

import collections
import os
import queue
import select
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from typing import Dict, Optional, Sequence, Tuple, Union

import numpy as np

from .errors import Sim4cvError
from . import proctree
from . import trax_protocol as tp

SPEC_PREFIX = "trax:"
_TAIL_LINES = 20
_MAX_LINE_BYTES = 1 << 20    # a longer line (stdout or stderr) keeps its first MiB: the client's memory stays bounded
_MAX_PENDING_LINES = 64      # unread protocol lines beyond this: the tracker floods, it is killed


class TraxError(Sim4cvError):
    """The TraX tracker failed: it exited or crashed, printed a malformed
    message, did not answer in time, reported an error or quit, or speaks a
    version or format sim4cv does not. The process has been killed."""


def parse_tracker_spec(spec: str) -> str:
    """The command line of a "trax:COMMAND LINE" tracker specification, or
    of an "octave:FILE.m" one (octave_command)."""
    if spec.startswith(OCTAVE_PREFIX):
        return octave_command(spec[len(OCTAVE_PREFIX):])
    if not spec.startswith(SPEC_PREFIX) or not spec[len(SPEC_PREFIX):].strip():
        raise ValueError("a TraX tracker is given as 'trax:COMMAND LINE' or 'octave:FILE.m', not %r" % (spec,))
    return spec[len(SPEC_PREFIX):].strip()


def open_tracker(spec: str, **options) -> "TraxTracker":
    """TraxTracker(parse_tracker_spec(spec), **options)."""
    return TraxTracker(parse_tracker_spec(spec), **options)


# "octave:FILE.m": a tracker in plain Octave (FILE.m defines tracker = NAME()
# with the handles init and update), run as a TraX server written in Octave,
# clients/matlab/trax/sim4cv_trax_server.m. See docs/trax.md, "Octave trackers".
OCTAVE_PREFIX = "octave:"
OCTAVE_SERVER_DIR = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                 "..", "..", "matlab", "trax"))


def octave_command(file: str) -> str:
    """The TraX command line that runs the Octave tracker FILE.m (relative
    to the working directory): octave --eval of sim4cv_trax_server. ValueError
    for a name that is not FILE.m; TraxError if the file does not exist."""
    file = file.strip()
    if not file.endswith(".m") or len(file) < 3:
        raise ValueError("an Octave tracker is given as 'octave:FILE.m', not %r" % ("octave:" + file,))
    path = os.path.abspath(file)
    if not os.path.isfile(path):
        raise TraxError("Octave tracker file %s does not exist" % path)
    if not os.path.isfile(os.path.join(OCTAVE_SERVER_DIR, "sim4cv_trax_server.m")):
        raise TraxError("Octave trackers need %s/sim4cv_trax_server.m (the repository's clients/matlab/trax)"
                        % OCTAVE_SERVER_DIR)

    def literal(text):                       # an Octave single-quoted string
        return "'" + text.replace("'", "''") + "'"
    expr = "addpath(%s); sim4cv_trax_server(%s)" % (literal(OCTAVE_SERVER_DIR), literal(path))
    quoted = '"%s"' % expr.replace("\\", "\\\\").replace('"', '\\"')    # as shlex reads it back
    return "octave --no-gui --no-window-system --quiet --no-history --eval " + quoted


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(code).name
    except ValueError:
        return "signal %d" % code


class TraxTracker:
    """One tracker process speaking TraX (versions 1 to 4, one object).

    command_line: a string (split with shlex) or a list of arguments.
    timeout: seconds each call (hello, init, update) may take before the
        tracker is killed; startup_timeout (default: timeout) for the hello.
    env: variables added to this process's environment; cwd: its directory.
    image_format: None to choose from the tracker's hello (memory, then
        buffer, then path), or one of those to insist on it.
    transport: "stdio" (default) or "socket" (TRAX_SOCKET=port; the tracker
        connects to 127.0.0.1:port, and its stdout is only its own output).
    echo: copy the tracker's stderr and non-TraX stdout to our stderr.

    name / properties: trax.name and all properties of the hello; version;
    image_format and region_format: what was negotiated; elapsed: seconds the
    last init()/update() took, image encoding and pipe transfer included
    (all of it counts as the tracker's time); state_properties: the named
    arguments of the last state message."""

    def __init__(self, command_line: Union[str, Sequence[str]], timeout: float = 10.0,
                 env: Optional[Dict[str, str]] = None, cwd: Optional[str] = None, *,
                 image_format: Optional[str] = None, transport: str = "stdio",
                 startup_timeout: Optional[float] = None, echo: bool = False):
        self.args = shlex.split(command_line) if isinstance(command_line, str) else [str(a) for a in command_line]
        if not self.args:
            raise ValueError("empty TraX tracker command line")
        if transport not in ("stdio", "socket"):
            raise ValueError("transport must be 'stdio' or 'socket', not %r" % (transport,))
        if image_format is not None and image_format not in tp.IMAGE_FORMATS:
            raise ValueError("image_format must be one of %s, not %r" % (", ".join(tp.IMAGE_FORMATS), image_format))
        self.command = " ".join(shlex.quote(a) for a in self.args)
        self.timeout, self.transport, self.echo = float(timeout), transport, echo
        self.name, self.properties, self.version = None, {}, None
        self.image_format = self.region_format = None
        self.elapsed, self.state_properties = 0.0, {}
        self._broken = None              # the message of the failure that ended the session
        self._closed = False
        self._initialized = False
        self._frame_no = 0
        self._last_line = ""             # the last protocol line read, for error messages
        self._tmpdir = None
        self._last_file = None
        self._lines = queue.Queue()      # protocol lines (str), None at end of stream
        self._stderr_tail = collections.deque(maxlen=_TAIL_LINES)
        self._output_tail = collections.deque(maxlen=_TAIL_LINES)
        self._threads, self._sock, self._listener = [], None, None

        full_env = dict(os.environ)
        full_env.update({str(k): str(v) for k, v in (env or {}).items()})
        self._token = proctree.new_token()   # marks its descendants, even those that leave with setsid()
        full_env.update(proctree.marker(self._token))
        self._flooded = False
        if transport == "socket":
            self._listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            self._listener.bind(("127.0.0.1", 0))
            self._listener.listen(1)
            full_env["TRAX_SOCKET"] = str(self._listener.getsockname()[1])
        try:
            self.proc = subprocess.Popen(self.args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                         stderr=subprocess.PIPE, cwd=cwd, env=full_env, bufsize=0,
                                         start_new_session=True)   # its own process group, killed as one
        except OSError as e:
            self._closed = True
            if self._listener is not None:
                self._listener.close()
            raise TraxError("cannot start TraX tracker %s: %s" % (self.command, e)) from None
        self.pid = self.proc.pid
        self._reaped = False
        try:
            self._reader(self.proc.stdout, self._on_stdout_line, end=transport == "stdio")
            self._reader(self.proc.stderr, self._on_stderr_line, end=False)
            deadline = time.monotonic() + (startup_timeout if startup_timeout is not None else self.timeout)
            if transport == "socket":
                self._accept(deadline)
            self._hello(self._receive(deadline, "its hello"), image_format)
        except BaseException:                # TraxError has killed it already; anything else (^C) does here
            self._closed = True
            self._kill_and_reap()
            raise

    # -- public calls ---------------------------------------------------------

    def init(self, image: np.ndarray, box: Sequence[float]) -> None:
        """Initialises the tracker on image (HxWx3 uint8 RGB, or HxW gray) with box (x, y, w, h)."""
        start = time.monotonic()
        self._check_open()
        x, y, w, h = (float(v) for v in box)
        if not (w > 0 and h > 0):
            raise ValueError("TraX init box needs a positive width and height, not %r" % (tuple(box),))
        deadline = start + self.timeout
        region = (tp.format_rectangle if self.region_format == "rectangle" else tp.format_polygon_of_box)((x, y, w, h))
        img = self._encode_image(image)
        if self.version >= 4:      # v4: initialize carries the region; the image follows in a frame
            if self._initialized:  # an empty initialize forgets the objects of the last one
                self._send(tp.format_message("initialize"), deadline)
            self._send(tp.format_message("initialize", [region]), deadline)
            self._send(tp.format_message("frame", [img]), deadline)
        else:
            self._send(tp.format_message("initialize", [img, region]), deadline)
        self._state(deadline, "initialize")
        self._initialized = True
        self.elapsed = time.monotonic() - start

    def update(self, image: np.ndarray) -> Optional[Tuple[float, float, float, float]]:
        """Sends the next frame; returns the tracker's box (x, y, w, h), the
        bounding box of its polygon, or None if it answered a special region."""
        start = time.monotonic()
        self._check_open()
        if not self._initialized:
            raise TraxError("update() before init() on TraX tracker %s" % self.command)
        deadline = start + self.timeout
        self._send(tp.format_message("frame", [self._encode_image(image)]), deadline)
        box = self._state(deadline, "frame")
        self.elapsed = time.monotonic() - start
        return box

    def close(self) -> None:
        """Says quit, gives the tracker a moment to exit, then kills its whole
        process group and reaps it. Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._broken is None and self._alive():
            try:
                self._send(tp.format_message("quit"), time.monotonic() + min(self.timeout, 1.0))
            except TraxError:
                pass
            self._close_input()
            self._wait_exit(min(self.timeout, 2.0))
        self._kill_and_reap()

    def __enter__(self) -> "TraxTracker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        try:
            if not self._closed and hasattr(self, "proc"):
                self._broken = self._broken or "garbage-collected"
                self.close()
        except Exception:
            pass

    @property
    def stderr_tail(self):
        """The last lines the tracker wrote to stderr."""
        return list(self._stderr_tail)

    # -- the session ------------------------------------------------------------

    def _hello(self, msg: tp.Message, image_format: Optional[str]) -> None:
        if msg.name != "hello" or msg.arguments:
            self._fail("sent %r instead of its hello" % self._last_line)
        props = msg.properties
        self.properties = dict(props)
        self.name = props.get("trax.name")
        try:
            self.version = int(props.get("trax.version", "1"))
        except ValueError:
            self._fail("announced trax.version=%r, not an integer" % props.get("trax.version"))
        if not tp.MIN_VERSION <= self.version <= tp.MAX_VERSION:
            self._fail("speaks TraX version %d; sim4cv speaks versions %d to %d"
                       % (self.version, tp.MIN_VERSION, tp.MAX_VERSION))
        regions = tp.split_list(props.get("trax.region")) or ["rectangle"]
        self.region_format = next((f for f in tp.REGION_FORMATS if f in regions), None)
        if self.region_format is None:
            self._fail("accepts regions %s; sim4cv sends %s" % (",".join(regions), " or ".join(tp.REGION_FORMATS)))
        if self.version >= 2:
            channels = tp.split_list(props.get("trax.channels")) or ["color"]
            if channels != ["color"]:
                self._fail("needs image channels %s; sim4cv sends only color" % ",".join(channels))
        offered = tp.split_list(props.get("trax.image")) or ["path"]
        usable = [f for f in tp.IMAGE_FORMATS if f in offered and (f == "memory" or _have_cv2())]
        if image_format is not None:
            if image_format not in usable:
                self._fail("accepts images as %s, not %s%s" % (",".join(offered), image_format,
                           "" if image_format == "memory" or _have_cv2() else " (needs python3-opencv here)"))
            self.image_format = image_format
        elif usable:
            self.image_format = usable[0]
        else:
            self._fail("accepts images as %s; sim4cv sends memory, buffer or path%s" % (
                ",".join(offered), "" if _have_cv2() else " (buffer and path need python3-opencv)"))

    def _state(self, deadline: float, after: str) -> Optional[Tuple[float, float, float, float]]:
        msg = self._receive(deadline, "a state after %s" % after)
        if msg.name != "state" or len(msg.arguments) != 1:
            self._fail("answered %s with %r instead of a state with one region" % (after, self._last_line))
        try:
            region = tp.parse_region(msg.arguments[0])
        except ValueError as e:
            self._fail("answered %s with a bad region: %s (line %r)" % (after, e, self._last_line[:200]))
        if region.kind not in ("rectangle", "polygon", "special"):
            self._fail("answered %s with a %s region; sim4cv reads rectangle, polygon or special regions: %r"
                       % (after, region.kind, self._last_line[:200]))
        self.state_properties = dict(msg.properties)
        self._drop_last_file()
        return region.bounding_box()

    def _receive(self, deadline: float, what: str) -> tp.Message:
        remaining = deadline - time.monotonic()
        if self._flooded:
            self._fail("sent more than %d TraX lines nobody asked for (waiting for %s); killed it"
                       % (_MAX_PENDING_LINES, what))
        try:
            line = self._lines.get(timeout=max(remaining, 0.0)) if remaining > 0 else self._lines.get_nowait()
        except queue.Empty:
            self._fail("did not send %s within %.3g s; killed it" % (what, self.timeout))
        if line is None:
            self._fail_ended("before sending %s" % what)
        self._last_line = line
        try:
            msg = tp.parse_message(line)
        except tp.MessageError as e:
            self._fail("sent a malformed TraX line instead of %s: %s" % (what, e))
        if msg.name == "error":
            self._fail("reported an error: %s" % (" ".join(msg.arguments + ["%s=%s" % kv for kv in
                                                                              msg.properties.items()]) or line))
        if msg.name == "quit":
            reason = msg.properties.get("trax.reason")
            self._fail("quit the session%s" % (": " + reason if reason else " (no reason given)"))
        return msg

    # -- images -------------------------------------------------------------------

    def _encode_image(self, image: np.ndarray) -> str:
        image = np.asarray(image)
        if not (image.dtype == np.uint8 and (image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 3))):
            raise ValueError("TraX images are HxWx3 uint8 RGB or HxW uint8 gray, not %s %s" % (image.shape, image.dtype))
        if self.image_format == "memory":
            return tp.encode_memory_image(image)
        import cv2
        bgr = cv2.cvtColor(image, cv2.COLOR_RGB2BGR) if image.ndim == 3 else image
        if self.image_format == "buffer":
            ok, data = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, 1])
            if not ok:
                raise TraxError("cannot encode the frame for TraX tracker %s as PNG" % self.command)
            return tp.encode_buffer_image(data.tobytes(), "image/png")
        if self._tmpdir is None:
            self._tmpdir = tempfile.mkdtemp(prefix="sim4cv-trax-")
        self._frame_no += 1
        path = os.path.join(self._tmpdir, "frame-%08d.png" % self._frame_no)
        if not cv2.imwrite(path, bgr, [cv2.IMWRITE_PNG_COMPRESSION, 1]):
            raise TraxError("cannot write the frame for TraX tracker %s to %s" % (self.command, path))
        self._last_file = path
        return tp.encode_path_image(path)

    def _drop_last_file(self):
        """The tracker has answered: it no longer needs the file of the frame."""
        if self._last_file:
            try:
                os.unlink(self._last_file)
            except OSError:
                pass
            self._last_file = None

    # -- process and streams ----------------------------------------------------------

    def _reader(self, pipe, on_line, end: bool):
        read = pipe.recv if hasattr(pipe, "recv") else pipe.read

        def run():
            buf, scanned = bytearray(), 0        # lines end at \n only: a \r is part of the line
            skipping = False                     # inside an over-long line, after its kept start
            try:
                while True:
                    chunk = read(1 << 16)
                    if not chunk:
                        break
                    buf += chunk
                    while True:
                        eol = buf.find(b"\n", scanned)
                        if eol < 0 and len(buf) > _MAX_LINE_BYTES:
                            # no newline in sight: keep the line's start, drop the rest up to its end
                            on_line(buf[:_MAX_LINE_BYTES].decode("utf-8", "replace") + " [line cut at %d bytes]"
                                    % _MAX_LINE_BYTES)
                            buf, scanned, skipping = bytearray(), 0, True
                            break
                        if eol < 0:
                            scanned = len(buf)
                            break
                        if skipping:
                            skipping = False
                            del buf[:eol + 1]
                            scanned = 0
                            continue
                        on_line(buf[:eol].decode("utf-8", "replace"))
                        del buf[:eol + 1]
                        scanned = 0
            except (OSError, ValueError):
                pass
            if buf and not skipping:             # a last line without its newline still counts
                on_line(buf.decode("utf-8", "replace"))
            if end:
                self._lines.put(None)
        t = threading.Thread(target=run, daemon=True, name="trax-reader")
        t.start()
        self._threads.append(t)

    def _on_stdout_line(self, line: str):
        if self.transport == "stdio" and tp.is_message_line(line):
            self._queue_line(line)
        else:                                # the tracker's own output: the protocol ignores it
            self._output_tail.append(line)
            if self.echo:
                print("[trax %s] %s" % (self.args[0], line), file=sys.stderr)

    def _on_stderr_line(self, line: str):
        self._stderr_tail.append(line)
        if self.echo:
            print("[trax %s] %s" % (self.args[0], line), file=sys.stderr)

    def _queue_line(self, line: str):
        # a tracker answers one request at a time: lines beyond a few unread ones are a flood, not answers
        if self._lines.qsize() >= _MAX_PENDING_LINES:
            self._flooded = True
        else:
            self._lines.put(line)

    def _on_socket_line(self, line: str):
        if tp.is_message_line(line):
            self._queue_line(line)
        else:
            self._on_stdout_line(line)

    def _accept(self, deadline: float):
        self._listener.settimeout(0.05)
        while True:
            try:
                self._sock, _ = self._listener.accept()
                break
            except socket.timeout:
                if not self._alive():
                    self._fail_ended("before connecting to TRAX_SOCKET")
                if time.monotonic() > deadline:
                    self._fail("did not connect to TRAX_SOCKET within %.3g s; killed it" % self.timeout)
        self._listener.close()
        self._listener = None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock.settimeout(None)
        self._reader(self._sock, self._on_socket_line, end=True)

    def _send(self, text: str, deadline: float):
        """Writes the whole line by the deadline, without blocking past it."""
        data = memoryview(text.encode("utf-8"))
        fd = self._sock.fileno() if self._sock is not None else self.proc.stdin.fileno()
        if self._sock is None:
            os.set_blocking(fd, False)       # only we use this pipe end; the socket is shared with its reader
        ended = False
        while data:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                self._fail("did not read its input within %.3g s; killed it" % self.timeout)
            try:
                n = os.write(fd, data) if self._sock is None else self._sock.send(data, socket.MSG_DONTWAIT)
            except BlockingIOError:
                select.select([], [fd], [], min(remaining, 0.1))
                continue
            except (BrokenPipeError, ConnectionError):
                ended = True
                break
            data = data[n:]
        if ended:
            self._fail_ended("while we were writing to it")

    def _alive(self) -> bool:
        try:
            return os.waitid(os.P_PID, self.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is None
        except ChildProcessError:
            return False

    def _wait_exit(self, seconds: float) -> bool:
        end = time.monotonic() + seconds
        while self._alive():
            if time.monotonic() > end:
                return False
            time.sleep(0.01)
        return True

    def _close_input(self):
        for f in (self.proc.stdin,):
            try:
                f.close()
            except OSError:
                pass
        if self._sock is not None:
            try:
                self._sock.shutdown(socket.SHUT_WR)
            except OSError:
                pass

    def _kill_and_reap(self):
        if self._reaped:                          # once only: after the wait the pid may be someone else's
            return
        proctree.kill_tree(self.pid, self._token)  # the leader is not reaped yet: the group id is still ours
        self.proc.wait()
        self._reaped = True
        self._close_input()
        if self._sock is not None:
            try:
                self._sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        for t in self._threads:
            t.join(timeout=1.0)
        for f in (self.proc.stdout, self.proc.stderr):
            try:
                f.close()
            except OSError:
                pass
        for s in (self._sock, self._listener):
            if s is not None:
                s.close()
        self._cleanup_files()

    def _cleanup_files(self):
        if self._tmpdir:
            shutil.rmtree(self._tmpdir, ignore_errors=True)
            self._tmpdir = None

    def _check_open(self):
        if self._broken is not None:
            raise TraxError("TraX tracker %s is gone: %s" % (self.command, self._broken))
        if self._closed:
            raise TraxError("TraX tracker %s is closed" % self.command)

    def _describe_exit(self) -> str:
        code = self.proc.returncode
        if code is None:
            return "is still running"
        return "was killed by %s" % _signal_name(-code) if code < 0 else "exited with code %d" % code

    def _tails(self) -> str:
        for t in self._threads:
            t.join(timeout=1.0)
        parts = []
        if self._stderr_tail:
            parts.append("last stderr lines:\n    " + "\n    ".join(self._stderr_tail))
        if self._output_tail:
            parts.append("last stdout lines (not TraX):\n    " + "\n    ".join(self._output_tail))
        return ("\n" + "\n".join(parts)) if parts else " (no output on stderr)"

    def _fail_ended(self, when: str):
        """The tracker's message stream ended: report how the process ended."""
        exited = self._wait_exit(2.0)
        if exited:
            self._closed = True
            self._broken = "its stream ended"
            self._kill_and_reap()
            self._raise("%s %s%s" % (self._describe_exit(), when, self._tails()))
        self._fail("closed its TraX stream %s but is still running; killed it" % when)

    def _fail(self, what: str):
        """Kills the tracker, reaps it and raises TraxError('TraX tracker CMD WHAT ...')."""
        self._closed = True
        self._broken = what
        self._kill_and_reap()
        self._raise(what + self._tails())

    def _raise(self, text: str):
        message = "TraX tracker %s %s" % (self.command, text)
        self._broken = message
        raise TraxError(message) from None


_CV2 = None


def _have_cv2() -> bool:
    global _CV2
    if _CV2 is None:
        try:
            import cv2  # noqa: F401
            _CV2 = True
        except ImportError:
            _CV2 = False
    return _CV2
