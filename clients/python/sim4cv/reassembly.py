"""Reassembly of UDP FrameChunks into frame envelopes (docs/protocol.md 12.4).

Nothing a peer claims is trusted before it is checked: a chunk's sizes and
index must agree with how the daemon cuts frames (every chunk but the last
carries the same number of bytes, the datagram is at most 65,507 bytes and
at least 576), and memory grows only with the bytes that actually arrive, so
one forged chunk announcing a huge frame costs nothing."""

from typing import Optional

MAX_DATAGRAM_BYTES = 65507  # the largest UDP/IPv4 payload
# The smallest data a chunk other than the last carries: --udp-datagram-bytes
# is at least 576, less the daemon's largest chunk header (43 bytes).
MIN_CHUNK_DATA_BYTES = 576 - 43


class FrameReassembler:
    """Feeds FrameChunk messages in, gets whole frame envelopes (bytes) out.

    Counters: completed, dropped (frames given up because a newer one
    overtook them with chunks missing), invalid (self-contradicting chunks),
    stale (duplicates and stragglers of finished or older frames).
    """

    def __init__(self, max_frame_bytes: int = 256 << 20):
        self.max_frame_bytes = max_frame_bytes
        self.completed = 0
        self.dropped = 0
        self.invalid = 0
        self.stale = 0
        self.last_invalid = ""   # why the last invalid chunk was refused
        self._last_finished = 0  # frame_id of the last frame completed or given up
        self._frame_id = None    # frame in progress
        self._parts = None
        self._count = 0
        self._bytes = 0

    @property
    def in_progress(self) -> Optional[int]:
        """frame_id of the frame being assembled, or None."""
        return self._frame_id

    def _check(self, chunk) -> str:
        """Why `chunk` cannot be part of a frame the daemon sent, or ""."""
        size = len(chunk.data)
        count, index, total, offset = chunk.chunk_count, chunk.chunk_index, chunk.frame_bytes, chunk.offset
        if total == 0 or total > self.max_frame_bytes:
            return "chunk announces a %d-byte frame; frames have 1 to %d bytes" % (total, self.max_frame_bytes)
        most = -(-total // MIN_CHUNK_DATA_BYTES)
        if count == 0 or count > most:
            return "chunk announces %d chunks for a %d-byte frame; at most %d" % (count, total, most)
        if index >= count:
            return "chunk index %d is not below its chunk count %d" % (index, count)
        if size == 0 or size > MAX_DATAGRAM_BYTES or offset + size > total:
            return "chunk carries %d bytes at offset %d of a %d-byte frame" % (size, offset, total)
        if index + 1 < count and (offset != index * size or -(-total // size) != count):
            return ("chunk %d of %d carries %d bytes at offset %d: inconsistent with a %d-byte frame"
                    % (index, count, size, offset, total))
        if index + 1 == count and offset + size != total:
            return "last chunk ends at byte %d of a %d-byte frame" % (offset + size, total)
        return ""

    def add(self, chunk) -> Optional[bytes]:
        """Takes one FrameChunk; returns the frame envelope's bytes when this
        chunk completed a frame, else None."""
        problem = self._check(chunk)
        if problem:
            self.invalid += 1
            self.last_invalid = problem
            return None
        data = chunk.data
        count, index, total = chunk.chunk_count, chunk.chunk_index, chunk.frame_bytes
        frame_id = chunk.frame_id
        if self._frame_id is None:
            if frame_id <= self._last_finished and not (index == 0 and frame_id < self._last_finished):
                self.stale += 1  # a duplicate or straggler (chunk 0 of a lower id: LoadMap/Reset restarted ids)
                return None
            self._start(frame_id, count, total)
        elif frame_id > self._frame_id:
            self.dropped += 1  # the frame in progress will never be completed
            self._finish()
            self._start(frame_id, count, total)
        elif frame_id < self._frame_id:
            self.stale += 1
            return None
        if count != self._count or total != self._bytes or index in self._parts:
            self.stale += 1
            return None
        self._parts[index] = data
        if len(self._parts) < count:
            return None
        frame = b"".join(self._parts[i] for i in range(count))
        self._finish()
        if len(frame) != total:  # chunks of different sizes, each consistent alone
            self.invalid += 1
            self.last_invalid = "chunks of frame %d add up to %d bytes, not %d" % (frame_id, len(frame), total)
            return None
        self.completed += 1
        return frame

    def _start(self, frame_id, count, total):
        self._frame_id, self._count, self._bytes = frame_id, count, total
        self._parts = {}  # chunk index -> its data; memory only for what arrived

    def _finish(self):
        self._last_finished = self._frame_id
        self._frame_id = self._parts = None
