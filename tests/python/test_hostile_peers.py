"""The Python clients trust no peer: a fake daemon on a real socket sends
chunks whose sizes and indexes lie, and the client refuses each with a
message saying what was wrong, without allocating what the chunk claims."""

import socket
import threading
import tracemalloc

import sim4cv
from sim4cv import pb

HUGE = 256 << 20


def _chunk(frame_id, index, count, total, offset, data):
    return pb.Envelope(frame_chunk=pb.FrameChunk(frame_id=frame_id, chunk_index=index, chunk_count=count,
                                                 frame_bytes=total, offset=offset, data=data)).SerializeToString()


# (datagram, the start of the message the reassembler files for it)
HOSTILE = [
    (_chunk(1, 0, HUGE, HUGE, 0, b"x"), "chunk announces 268435456 chunks for a 268435456-byte frame; at most"),
    (_chunk(2, 0, 1, 0xFFFFFFFF, 0, b"x"), "chunk announces a 4294967295-byte frame; frames have 1 to"),
    (_chunk(3, 5, 4, 4000, 0, b"x" * 1000), "chunk index 5 is not below its chunk count 4"),
    (_chunk(4, 1, 3, 3000, 7, b"x" * 1000), "chunk 1 of 3 carries 1000 bytes at offset 7"),
    (_chunk(5, 0, 1, 100, 90, b"x" * 20), "chunk carries 20 bytes at offset 90 of a 100-byte frame"),
]


def _fake_daemon(server, frame, go):
    """Answers the Hello with a Welcome, then, once the test says go (it has
    started recording refusals), sends every hostile chunk and finally one
    honest frame in one chunk."""
    data, peer = server.recvfrom(65536)
    hello = pb.Envelope()
    hello.ParseFromString(data)
    server.sendto(pb.Envelope(welcome=pb.Welcome(client_id=7, protocol_version=1)).SerializeToString(), peer)
    go.wait(30.0)
    for datagram, _ in HOSTILE:
        server.sendto(datagram, peer)
    whole = pb.Envelope(frame=frame).SerializeToString()
    server.sendto(_chunk(9, 0, 1, len(whole), 0, whole), peer)


def test_udp_client_refuses_lying_chunks_without_allocating():
    server = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    server.bind(("127.0.0.1", 0))
    frame = pb.Frame(frame_id=9, camera="honest")
    go = threading.Event()
    fake = threading.Thread(target=_fake_daemon, args=(server, frame, go), daemon=True)
    fake.start()
    tracemalloc.start()
    try:
        client = sim4cv.connect("udp://127.0.0.1:%d" % server.getsockname()[1], name="victim", timeout=10.0)
        problems = []
        original = client.reassembler.add

        def add(chunk):  # records each refusal's message as it is filed
            result = original(chunk)
            problems.append(client.reassembler.last_invalid)
            return result
        client.reassembler.add = add
        go.set()  # before this, the client's receiver could take a chunk the wrapper never saw
        received = client.receive_frame(timeout=10.0)
        _, peak = tracemalloc.get_traced_memory()
        client.close()
    finally:
        tracemalloc.stop()
        server.close()
    assert received.frame_id == 9
    assert client.reassembler.invalid == len(HOSTILE) and client.reassembler.completed == 1
    for (_, expected), got in zip(HOSTILE, problems):
        assert got.startswith(expected), (got, expected)
    assert peak < 16 << 20, "the client allocated %d bytes for forged chunks" % peak


# A fake shared-memory daemon: listens on the abstract socket of --shm-name
# NAME and answers the attach with `status` and the claimed sizes, passing
# three small memfds.
FAKE_SHM = r"""
import os, socket, struct, sys
sys.path.insert(0, sys.argv[1])
from sim4cv import shm_layout as L
server = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
server.bind(L.socket_address(sys.argv[2]))
server.listen(1)
print("ready", flush=True)
peer, _ = server.accept()
fds = [os.memfd_create("fake%d" % i) for i in range(3)]
for fd in fds:
    os.ftruncate(fd, 4096)
message = struct.pack("<8sIIQQ224s", L.ATTACH_MAGIC, L.LAYOUT_VERSION, 0, 1 << 40, L.AREA_BYTES, b"")
socket.send_fds(peer, [message], fds)
peer.recv(1)
"""


def _fake_shm_daemon(name, user=None):
    import os
    import subprocess
    import sys
    package = os.path.dirname(os.path.dirname(os.path.abspath(sim4cv.__file__)))
    fake = subprocess.Popen([sys.executable, "-c", FAKE_SHM, package, name], stdout=subprocess.PIPE, text=True,
                            user=user)
    assert fake.stdout.readline().strip() == "ready"
    return fake


def _attach_error(name):
    try:
        sim4cv.connect("shm://" + name, name="victim", timeout=5.0)
    except (sim4cv.ConnectionClosed, sim4cv.ShmLayoutError) as e:
        return str(e)
    raise AssertionError("attached to a fake daemon")


def test_shm_client_refuses_a_socket_of_another_user():
    import os
    import pytest
    if os.getuid() != 0:
        pytest.skip("needs root to run the fake daemon as user nobody")
    name = "/hostile-owner-%d" % os.getpid()
    fake = _fake_shm_daemon(name, user="nobody")
    try:
        message = _attach_error(name)
    finally:
        fake.kill()
        fake.wait()
    assert "belongs to process %d of uid 65534, not to this user (uid 0)" % fake.pid in message, message


def test_shm_client_checks_claimed_sizes_before_mapping():
    import os
    name = "/hostile-size-%d" % os.getpid()
    fake = _fake_shm_daemon(name)
    try:
        message = _attach_error(name)
    finally:
        fake.kill()
        fake.wait()
    assert "the frame object is said to be 1099511627776 bytes but its descriptor holds 4096" in message, message
