"""Reassembly of UDP FrameChunks into frame envelopes (docs/protocol.md 12.4)."""

from typing import Optional


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
        self._last_finished = 0  # frame_id of the last frame completed or given up
        self._frame_id = None    # frame in progress
        self._buffer = None
        self._received = None
        self._missing = 0
        self._count = 0
        self._bytes = 0

    @property
    def in_progress(self) -> Optional[int]:
        """frame_id of the frame being assembled, or None."""
        return self._frame_id

    def add(self, chunk) -> Optional[bytearray]:
        """Takes one FrameChunk; returns the frame envelope's bytes when this
        chunk completed a frame, else None."""
        data = chunk.data
        count, index, total, offset = chunk.chunk_count, chunk.chunk_index, chunk.frame_bytes, chunk.offset
        if (count == 0 or index >= count or total == 0 or total > self.max_frame_bytes or count > total
                or not data or offset + len(data) > total):
            self.invalid += 1
            return None
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
        if count != self._count or total != self._bytes or self._received[index]:
            self.stale += 1
            return None
        self._received[index] = True
        self._buffer[offset:offset + len(data)] = data
        self._missing -= 1
        if self._missing:
            return None
        frame = self._buffer
        self.completed += 1
        self._finish()
        return frame

    def _start(self, frame_id, count, total):
        self._frame_id, self._count, self._bytes = frame_id, count, total
        self._buffer = bytearray(total)
        self._received = [False] * count
        self._missing = count

    def _finish(self):
        self._last_finished = self._frame_id
        self._frame_id = self._buffer = self._received = None
