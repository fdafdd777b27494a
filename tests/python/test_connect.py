"""sim4cv.connect(address): the address forms, bad addresses, connecting to
nothing over each transport, and reconnect=True across a daemon restart."""

import socket
import time

import pytest

import sim4cv
from conftest import unique_shm_name


@pytest.mark.parametrize("text, expected", [
    ("tcp://127.0.0.1:5000", sim4cv.Address("tcp", "127.0.0.1", 5000)),
    ("TCP://localhost:1", sim4cv.Address("tcp", "localhost", 1)),
    ("udp://[::1]:5001", sim4cv.Address("udp", "::1", 5001)),
    ("udp://sim-host.example:65535", sim4cv.Address("udp", "sim-host.example", 65535)),
    ("shm:///sim4cv-demo", sim4cv.Address("shm", name="/sim4cv-demo")),
    ("shm://sim4cv-demo", sim4cv.Address("shm", name="/sim4cv-demo")),
])
def test_address_forms(text, expected):
    parsed = sim4cv.parse_address(text)
    assert parsed == expected
    assert sim4cv.parse_address(str(parsed)) == parsed


@pytest.mark.parametrize("text", [
    "", "127.0.0.1:5000", "http://127.0.0.1:80", "tcp://127.0.0.1", "tcp://127.0.0.1:0", "udp://host:70000",
    "tcp://:5000", "tcp://host:port", "shm://", "shm:///", "shm:///a/b", "shm://" + "x" * 97, "tcp//host:1",
])
def test_bad_addresses_name_the_address_and_the_forms(text):
    with pytest.raises(ValueError) as info:
        sim4cv.connect(text)
    message = str(info.value)
    assert repr(text) in message and "tcp://HOST:PORT" in message and "shm://NAME" in message


def _free_port(kind):
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("address, transport", [
    ("tcp://127.0.0.1:%d" % _free_port(socket.SOCK_STREAM), "TCP"),
    ("udp://127.0.0.1:%d" % _free_port(socket.SOCK_DGRAM), "UDP"),
    ("shm://" + unique_shm_name(), "shared memory"),
])
def test_connecting_to_nothing_fails_fast_naming_address_and_transport(address, transport):
    start = time.monotonic()
    with pytest.raises(sim4cv.ConnectionClosed) as info:
        sim4cv.connect(address, timeout=120.0)
    assert time.monotonic() - start < 60  # refused at once (ICMP port unreachable for UDP), not after the timeout
    assert address in str(info.value) and transport in str(info.value)


def test_udp_hello_is_retried_every_quarter_second_until_the_timeout():
    silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)  # takes datagrams, never answers
    silent.bind(("127.0.0.1", 0))
    address = "udp://127.0.0.1:%d" % silent.getsockname()[1]
    start = time.monotonic()
    with pytest.raises(sim4cv.ConnectionClosed) as info:
        sim4cv.connect(address, timeout=1.0)
    elapsed = time.monotonic() - start
    assert 0.9 < elapsed < 20 and address in str(info.value) and "UDP" in str(info.value)
    silent.setblocking(False)
    hellos = []
    while True:
        try:
            hellos.append(sim4cv.decode_envelope(silent.recv(65536)))
        except BlockingIOError:
            break
    silent.close()
    assert 4 <= len(hellos) <= 6, len(hellos)  # at 0, 0.25, 0.5, 0.75 (and maybe 1.0) s
    assert all(h.WhichOneof("kind") == "hello" for h in hellos)
    assert [h.sequence for h in hellos] == list(range(1, len(hellos) + 1))


def test_reconnect_after_a_daemon_restart_on_the_same_port(start_daemon):
    first = start_daemon()
    client = sim4cv.connect("tcp://127.0.0.1:%d" % first.port, name="phoenix", reconnect=True)
    start_daemon.clients.append(client)
    client.subscribe("uav", ["rgb", "boxes"], "lockstep")
    assert [client.step_and_receive().frame_id for _ in range(3)] == [1, 2, 3]
    assert first.terminate() == 0
    second = start_daemon("--tcp-port", str(first.port))
    frame = client.step_and_receive()  # reconnects, Hello, Subscribe, Step
    assert frame.frame_id == 1 and frame.image("rgb").shape == (180, 320, 3)
    assert client.reconnects == 1 and client.welcome.client_id >= 1
    assert client.step_and_receive().frame_id == 2
    assert second.proc.poll() is None


def test_without_reconnect_a_restart_raises_connection_closed(start_daemon):
    first = start_daemon()
    client = sim4cv.connect("tcp://127.0.0.1:%d" % first.port)
    start_daemon.clients.append(client)
    client.subscribe("uav", ["rgb"], "lockstep")
    client.step_and_receive()
    assert first.terminate() == 0
    with pytest.raises(sim4cv.ConnectionClosed):
        client.step_and_receive(timeout=2.0)
    with pytest.raises(sim4cv.ConnectionClosed):
        client.get_state()
