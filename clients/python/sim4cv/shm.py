"""The common client API over sim4cvd's shared-memory ring (docs/protocol.md
section 13): frames are read in place from the read-only frame object
(ShmFrame: zero-copy numpy views checked with the slot's seqlock), requests
go through the client's own request ring + doorbell, replies come back
through its response ring. Configure goes over a companion TCP connection.
"""

import collections
import mmap
import os
import platform
import select
import socket
import struct
import time

import numpy as np

from . import shm_layout as L
from ._proto import pb
from .base import KEEPALIVE_INTERVAL_S, BaseClient, envelope
from .client import Client
from .errors import ConnectionClosed, ServerError, ShmLayoutError, StaleFrameError
from .frame import Box, EntityPose, Frame
from .images import channel_name, channel_value, plane_view

_FUTEX = platform.system() == "Linux" and platform.machine() in ("x86_64", "AMD64")
_WAIT_SLICE_S = 0.1  # longest single sleep: liveness is checked between them
_DOORBELL = struct.pack("<Q", 1)


class ShmFrame(Frame):
    """A frame read in place from a ring slot. image(channel) is a read-only
    numpy view of the slot (no copy), valid until the daemon reuses the slot
    (slot_count - 1 frames later at the earliest): check() raises
    StaleFrameError once the daemon has begun overwriting it, and image()
    checks first. Use the pixels, then check() before trusting results; or
    copy() for a frame that owns its pixels."""

    __slots__ = ("publication", "_ring", "_sequence_index", "_sequence", "_planes")

    def __init__(self, ring, slot_base, sequence, head, planes, boxes, entities):
        (_, publication, frame_id, sim_time, render_end, width, height) = head[:7]
        super().__init__(frame_id, sim_time, render_end, width, height, boxes, entities, None, None,
                         ring.geometry.camera_name)
        self.publication = publication
        self._ring = ring
        self._sequence_index = slot_base // 8
        self._sequence = sequence
        self._planes = planes  # channel -> (offset in object, stride, element, components)

    @property
    def channels(self):
        return list(self._planes)

    @property
    def stale(self) -> bool:
        """True once the daemon has begun overwriting this frame's slot."""
        return int(self._ring.words64[self._sequence_index]) != self._sequence

    def check(self) -> None:
        """Raises StaleFrameError if the slot no longer holds this frame:
        whatever was computed from its views since must be discarded."""
        if self.stale:
            raise StaleFrameError("frame %d's shared-memory slot was overwritten by a newer frame (the ring has "
                                  "%d slots): discard what you computed from its views, or copy() frames you keep"
                                  % (self.frame_id, self._ring.geometry.slot_count))

    def image(self, channel) -> np.ndarray:
        """Zero-copy read-only view of `channel` in the slot (StaleFrameError if stale)."""
        self.check()
        try:
            offset, stride, element, components = self._planes[channel_value(channel)]
        except KeyError:
            raise KeyError("frame %d does not carry channel %s (the ring carries %s)" % (
                self.frame_id, channel_name(channel),
                ", ".join(channel_name(c)[8:].lower() for c in self._planes))) from None
        return self._ring.view(offset, self.width, self.height, stride, element, components, channel)

    def copy(self) -> Frame:
        """A Frame owning copies of every plane, taken consistently
        (StaleFrameError if the slot was overwritten meanwhile)."""
        images = {c: self.image(c).copy() for c in self._planes}
        self.check()
        return Frame(self.frame_id, self.sim_time, self.render_end_mono_ns, self.width, self.height,
                     list(self.boxes), list(self.entities), images, None, self.camera)


def _check_peer_is_us(sock, address):
    """The abstract socket name is anyone's to take: attach only to a
    process of our own user (SO_PEERCRED of the listening end), as the
    daemon accepts only clients of its own user."""
    pid, uid, _ = struct.unpack("3i", sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i")))
    if uid != os.getuid():
        raise ConnectionClosed("refusing to attach to %s: the socket @%s%s belongs to process %d of uid %d, "
                               "not to this user (uid %d); another user may be impersonating sim4cvd"
                               % (address, L.SOCKET_PREFIX, address.name, pid, uid, os.getuid()))


def _check_mappable(fd, claimed, which, what):
    """A size the peer claims is checked against the descriptor's real size
    before mapping: touching pages past the end would kill us with SIGBUS."""
    actual = os.fstat(fd).st_size
    if claimed <= 0 or claimed > actual:
        raise ShmLayoutError("%s: %s is said to be %d bytes but its descriptor holds %d" % (what, which, claimed, actual))


class _Ring:
    """The mapped, validated frame object."""

    def __init__(self, fd, size, what):
        self.frames = mmap.mmap(fd, size, mmap.MAP_SHARED, mmap.PROT_READ)
        self.geometry = L.parse_ring_header(self.frames, size, what)
        self.words64 = np.frombuffer(self.frames, dtype="<u8", count=size // 8)
        self.words32 = np.frombuffer(self.frames, dtype="<u4", count=size // 4)
        self.address = self.words32.ctypes.data
        # Views of the slots' planes: the same few (slot x channel) every frame, so made once.
        self._views = {}
        self._channel_records = struct.Struct("<" + L.CHANNEL_RECORD.format.lstrip("<") * L.MAX_CHANNELS)

    def view(self, offset, width, height, stride, element, components, channel):
        """A read-only numpy view of a plane of the mapped object (made once per plane place and shape)."""
        key = (offset, width, height, stride, element, components)
        view = self._views.get(key)
        if view is None:
            view = self._views[key] = plane_view(self.frames, offset, width, height, stride, element, components,
                                                 "shared-memory plane of %s" % channel_name(channel))
        return view

    def published(self):
        return int(self.words64[L.OFF_PUBLISHED // 8])

    def futex_word(self):
        return int(self.words32[L.OFF_FRAME_FUTEX // 4])

    def closed(self):
        return int(self.words32[L.OFF_CLOSED // 4]) != 0

    def read_newest(self):
        """The newest frame as a ShmFrame (seqlock-checked header), or None."""
        g = self.geometry
        for _ in range(10000):
            p = self.published()
            if p == 0:
                return None
            base = g.slots_offset + ((p - 1) % g.slot_count) * g.slot_bytes
            s1 = int(self.words64[base // 8])
            if s1 & 1:
                continue  # being rewritten: microseconds
            head = L.SLOT_HEAD.unpack_from(self.frames, base)
            mask, box_count, entity_count = head[7], min(head[9], L.MAX_BOXES), min(head[11], L.MAX_ENTITIES)
            planes = {}
            records = self._channel_records.unpack_from(self.frames, base + L.OFF_CHANNELS)
            for i in range(0, len(records), 8):  # 8 fields a record
                channel, _, stride, _, element, components, offset, nbytes = records[i:i + 8]
                if nbytes and mask & (1 << channel) and g.plane_offsets.get(channel) == offset \
                        and nbytes <= g.slot_bytes - offset:
                    planes[channel] = (base + offset, stride, element, components)
            boxes = [Box(*b) for b in L.BOX.iter_unpack(self.frames[base + L.OFF_BOXES:
                                                                    base + L.OFF_BOXES + 32 * box_count])]
            entities = []
            for e in L.ENTITY.iter_unpack(self.frames[base + L.OFF_ENTITIES:base + L.OFF_ENTITIES + 112 * entity_count]):
                entities.append(EntityPose(e[0], e[1], e[2:5], e[5:9], e[9:12], e[12:15]))
            if int(self.words64[base // 8]) != s1:
                continue  # torn: the slot changed while we read it
            if head[5] != g.width or head[6] != g.height:
                raise ShmLayoutError("slot of frame %d is %dx%d, the ring %dx%d" % (
                    head[2], head[5], head[6], g.width, g.height))
            return ShmFrame(self, base, s1, head, planes, boxes, entities)
        raise TimeoutError("could not read a consistent shared-memory frame")


class ShmClient(BaseClient):
    """sim4cv.connect("shm://NAME"): attaches to the ring of a daemon started
    with --shm-name NAME. .ring_geometry describes the ring (camera name,
    size, channels). Frames are ShmFrames (zero-copy) unless copy=True."""

    transport = "shm"

    def __init__(self, address, name="python-client", timeout=5.0, reconnect=False,
                 keepalive_interval=KEEPALIVE_INTERVAL_S, use_futex=_FUTEX):
        super().__init__(address, name, timeout, reconnect)
        self.keepalive_interval = keepalive_interval
        self.use_futex = use_futex
        self.responses_lost = 0
        self._ring = None
        self._sock = self._area = self._area64 = self._area32 = None
        self._doorbell = -1
        self._requests = self._responses = 0
        self._replies = collections.deque()
        self._keepalive_states = 0
        self._last_send = 0.0
        self._last_publication = 0
        self._tcp = None  # companion TCP connection for configure()

    @property
    def ring_geometry(self) -> L.RingGeometry:
        return self._ring.geometry

    # -- attaching ---------------------------------------------------------
    def _open(self, timeout):
        what = "the shared-memory ring %s" % self.address.name
        if self._sock is not None:
            self._close_attachment_only()
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        try:
            sock.settimeout(timeout)
            sock.connect(L.socket_address(self.address.name))
            _check_peer_is_us(sock, self.address)
            message, fds, _, _ = socket.recv_fds(sock, L.ATTACH_BYTES, 3)
        except ConnectionClosed:
            sock.close()
            raise
        except (OSError, socket.timeout) as e:
            sock.close()
            raise ConnectionClosed("cannot attach to sim4cvd at %s (shared memory, socket @%s%s): %s" % (
                self.address, L.SOCKET_PREFIX, self.address.name, getattr(e, "strerror", None) or e)) from e
        try:
            status, frames_bytes, area_bytes, reason = L.parse_attach(message, what)
            if status != 0 or len(fds) != 3:
                raise ConnectionClosed("sim4cvd at %s refused the shared-memory attachment: %s" % (
                    self.address, reason or "%d descriptors" % len(fds)))
            _check_mappable(fds[0], frames_bytes, "the frame object", what)
            _check_mappable(fds[1], area_bytes, "the client area", what)
            if self._ring is None:  # attached again: keep the mapping that frames may point into
                self._ring = _Ring(fds[0], frames_bytes, what)
            if area_bytes < L.AREA_BYTES:
                raise ShmLayoutError("%s: the client area is %d bytes, expected %d" % (what, area_bytes, L.AREA_BYTES))
            area = mmap.mmap(fds[1], L.AREA_BYTES, mmap.MAP_SHARED, mmap.PROT_READ | mmap.PROT_WRITE)
            L.check_area_header(area)
        except BaseException:
            for fd in fds:
                os.close(fd)
            sock.close()
            raise
        os.close(fds[0])
        os.close(fds[1])
        sock.setblocking(False)  # long responses are read only once the ring says they are there
        self._sock, self._area, self._doorbell = sock, area, fds[2]
        self._area64 = np.frombuffer(area, dtype="<u8")
        self._area32 = np.frombuffer(area, dtype="<u4")
        self._area_address = self._area32.ctypes.data
        self._requests = self._responses = 0
        self._replies.clear()
        self._keepalive_states = 0
        self._last_publication = self._ring.published()

    def _close(self):
        if self._doorbell >= 0:
            os.close(self._doorbell)
            self._doorbell = -1
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        self._area64 = self._area32 = self._area = None  # the mmap closes once nothing views it
        if self._tcp is not None:
            self._tcp.close()
            self._tcp = None

    def _attached(self, check_socket=True):
        if self._area32 is None or self._area32[L.OFF_AREA_CLOSED // 4]:
            return False
        if check_socket:
            readable, _, _ = select.select([self._sock], [], [], 0)
            if readable:
                try:
                    if not self._sock.recv(1, socket.MSG_DONTWAIT | socket.MSG_PEEK):
                        return False
                except BlockingIOError:
                    pass
                except OSError:
                    return False
        return True

    def _require_attached(self, check_socket=True):
        if self._area32 is None:
            raise ConnectionClosed("not attached to sim4cvd at %s" % (self.address,))
        if self._ring.closed():
            self._open_now = False
            raise ConnectionClosed("sim4cvd at %s stopped: the shared-memory ring is closed" % (self.address,))
        if not self._attached(check_socket):
            self._read_responses()  # the daemon's last word (e.g. expiry) if it left one
            self._raise_errors()
            self._open_now = False
            raise ConnectionClosed("sim4cvd ended this client's shared-memory attachment to %s (it stopped or was "
                                   "killed, or the client was silent for --shm-expiry-ms); hello() attaches again"
                                   % (self.address,))

    # -- request and response rings --------------------------------------
    def _send(self, env):
        data = env.SerializeToString()
        if len(data) > L.REQUEST_DATA_BYTES:
            raise ValueError("the encoded %s is %d bytes; a shared-memory request slot holds at most %d" % (
                env.WhichOneof("kind"), len(data), L.REQUEST_DATA_BYTES))
        self._require_attached(False)
        give_up = time.monotonic() + 5.0
        while self._requests - int(self._area64[L.OFF_REQUEST_READ // 8]) >= L.REQUEST_CAPACITY:
            self._require_attached()
            if time.monotonic() > give_up:
                raise ConnectionClosed("sim4cvd at %s took none of this client's queued requests for 5 s"
                                       % (self.address,))
            time.sleep(0.0005)
        slot = L.REQUEST_OFFSET + (self._requests % L.REQUEST_CAPACITY) * L.REQUEST_SLOT_BYTES
        struct.pack_into("<I", self._area, slot, len(data))
        self._area[slot + 8:slot + 8 + len(data)] = data
        self._requests += 1
        self._area64[L.OFF_REQUEST_WRITE // 8] = self._requests  # one aligned 8-byte store, after the slot
        try:
            os.write(self._doorbell, _DOORBELL)
        except OSError:
            pass  # the daemon also polls every 100 ms
        self._last_send = time.monotonic()

    def _read_responses(self):
        """Moves every complete response from the ring into self._replies."""
        area, words = self._area, self._area64
        if words is None:
            return
        while True:
            written = int(words[L.OFF_RESPONSES_WRITTEN // 8])
            if self._responses >= written:
                return
            if written - self._responses > L.RESPONSE_DEPTH:
                self.responses_lost += written - L.RESPONSE_DEPTH - self._responses
                self._responses = written - L.RESPONSE_DEPTH
                self._discard_long_responses_before(self._responses)
            k = self._responses
            base = L.RESPONSE_OFFSET + (k % L.RESPONSE_DEPTH) * L.RESPONSE_MESSAGE_BYTES
            s1 = int(words[base // 8])
            size, on_socket = struct.unpack_from("<II", area, base + 8)
            data = b"" if on_socket else \
                area[base + L.RESPONSE_DATA_OFFSET:base + L.RESPONSE_DATA_OFFSET + min(size, L.RESPONSE_DATA_BYTES)]
            if s1 != 2 * k + 2 or int(words[base // 8]) != s1:
                continue  # being written, or overwritten while copied: look again
            self._responses += 1
            if on_socket:
                data = self._long_response(k, size)
            env = pb.Envelope()
            try:
                if data is None:
                    raise ValueError("response %d is not on the socket" % k)
                env.ParseFromString(data)
            except Exception:
                self.responses_lost += 1
                continue
            kind = env.WhichOneof("kind")
            if kind == "state" and self._keepalive_states:
                self._keepalive_states -= 1  # the answer to a keep-alive GetState
                continue
            self._replies.append((kind, getattr(env, kind) if kind else None))

    def _discard_long_responses_before(self, k):
        """After falling a lap behind: drops the socket messages of responses
        the ring overwrote, so they no longer fill the socket."""
        while True:
            try:
                head = self._sock.recv(L.SOCKET_RESPONSE_HEADER_BYTES, socket.MSG_DONTWAIT | socket.MSG_PEEK)
            except OSError:
                return
            if len(head) != L.SOCKET_RESPONSE_HEADER_BYTES or struct.unpack("<Q", head)[0] >= k:
                return
            self._sock.recv(L.SOCKET_RESPONSE_HEADER_BYTES, socket.MSG_DONTWAIT)  # the rest goes too

    def _long_response(self, k, size):
        """Response k's Envelope from the socket, where the ring says it is
        (the daemon sent it before announcing it); None if it is not there."""
        if size > L.SOCKET_RESPONSE_BYTES:
            return None  # a daemon never announces one: nothing is allocated for it
        while True:
            try:
                # The buffer is this client's own bound, never what the peer claims.
                message, _, flags, _ = self._sock.recvmsg(
                    L.SOCKET_RESPONSE_HEADER_BYTES + L.SOCKET_RESPONSE_BYTES, 0, socket.MSG_DONTWAIT)
            except OSError:
                return None
            if len(message) < L.SOCKET_RESPONSE_HEADER_BYTES or flags & socket.MSG_TRUNC:
                return None
            tag = struct.unpack_from("<Q", message)[0]
            if tag < k:
                continue  # its response was overwritten in the ring before we read it
            body = message[L.SOCKET_RESPONSE_HEADER_BYTES:]
            return body if tag == k and len(body) == size else None

    def _raise_errors(self):
        for item in list(self._replies):
            if item[0] == "error":
                self._replies.remove(item)
                raise ServerError.from_message(item[1])

    def _wait(self, ready, timeout, frames):
        """Until ready() returns something: reads responses, raises Errors,
        keeps the attachment alive, sleeps on the frame futex (`frames`) or
        the response futex."""
        if frames:
            word, address = self._ring.futex_word, self._ring.address + L.OFF_FRAME_FUTEX
        else:
            word, address = self._response_futex, self._area_address + L.OFF_RESPONSE_FUTEX
        start = time.monotonic()
        deadline = None if timeout is None else start + timeout
        while True:
            if time.monotonic() - self._last_send >= self.keepalive_interval:
                # Before anything else: a reader whose frames are always
                # there at once never waits, yet must be heard from.
                self._keepalive_states += 1
                self._send(envelope(get_state=pb.GetState()))
            seen = word()
            self._read_responses()
            self._raise_errors()
            result = ready()
            if result is not None:
                return result
            now = time.monotonic()
            self._require_attached(check_socket=now - start > 0.05)
            if deadline is not None and now >= deadline:
                raise TimeoutError("nothing from sim4cvd at %s (shared memory) within %.2f s"
                                   % (self.address, timeout))
            nap = min(_WAIT_SLICE_S, self._last_send + self.keepalive_interval - now,
                      _WAIT_SLICE_S if deadline is None else deadline - now)
            if self.use_futex:
                L.futex_wait(address, seen, nap)
            else:
                time.sleep(min(nap, 0.0005))

    def _response_futex(self):
        return int(self._area32[L.OFF_RESPONSE_FUTEX // 4]) if self._area32 is not None else 0

    # -- hooks -------------------------------------------------------------
    def _exchange(self, env, kind, timeout):
        if kind == "welcome" and not self._attached():
            self._close_attachment_only()
            self._open(timeout)
        self._send(env)

        def reply():
            for item in self._replies:
                if item[0] == kind:
                    self._replies.remove(item)
                    return item[1]
            return None
        result = self._wait(reply, timeout, False)
        if kind == "subscribed":
            self._last_publication = self._ring.published()  # frames from now on
        return result

    def _close_attachment_only(self):
        tcp, self._tcp = self._tcp, None
        self._close()
        self._tcp = tcp

    def _newest_frame(self, timeout, copy):
        ring = self._ring

        def newer():
            if ring.published() <= self._last_publication:
                return None
            return ring.read_newest()
        frame = self._wait(newer, timeout, True)
        self._last_publication = frame.publication
        return frame.copy() if copy else frame

    _next_frame = _newest_frame  # lockstep: the frame our Step produced is the newest

    def _configure(self, request, request_id, timeout):
        if self._tcp is None:
            ports = [t.address for t in self.welcome.transports if t.kind == pb.TRANSPORT_KIND_TCP] \
                if self.welcome is not None else []
            if not ports:
                raise ConnectionClosed("sim4cvd at %s offers no TCP port for Configure (Welcome.transports)"
                                       % (self.address,))
            tcp = Client()
            try:
                tcp.connect("127.0.0.1", int(ports[0]), self.name + "/configure", self.timeout)
            except OSError as e:
                tcp.close()
                raise ConnectionClosed("cannot open the companion TCP connection for Configure to "
                                       "127.0.0.1:%s: %s" % (ports[0], e)) from e
            self._tcp = tcp
        self._tcp._last_request_id = request_id - 1
        return self._tcp.configure(request, timeout)
