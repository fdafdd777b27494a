"""A minimal WebSocket client over a plain socket (RFC 6455), so the tests
can also send what no well-behaved library would: unmasked or reserved
frames, oversized messages, and stop reading altogether.

    ws = RawWebSocket(port)                 # the upgrade to /ws
    ws.send_json({"hello": {...}})
    kind, payload = ws.receive()            # ("text", str) / ("binary", bytes) / ("close", (code, reason))
"""

import base64
import json
import os
import socket
import struct
import time

from sim4cv.access import access_token


class HandshakeRefused(Exception):
    """The upgrade was answered with an HTTP status other than 101."""

    def __init__(self, status, body):
        super().__init__("HTTP %s: %s" % (status, body))
        self.status, self.body = status, body


def http_get(port, path, headers=None, timeout=10.0):
    """(status, headers dict, body bytes) of one GET over a fresh connection."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    lines = ["GET %s HTTP/1.1" % path, "Host: 127.0.0.1:%d" % port, "Connection: close"]
    lines += ["%s: %s" % item for item in (headers or {}).items()]
    sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
    data = b""
    while True:
        chunk = sock.recv(65536)
        if not chunk:
            break
        data += chunk
    sock.close()
    head, _, body = data.partition(b"\r\n\r\n")
    status_line, *header_lines = head.decode("latin-1").split("\r\n")
    parsed = {k.strip().lower(): v.strip() for k, _, v in (h.partition(":") for h in header_lines)}
    return int(status_line.split()[1]), parsed, body


class RawWebSocket:
    def __init__(self, port, path="/ws", host=None, origin=None, timeout=10.0, hello=None, cookie=None, token=None):
        """hello: say Hello with this client name; token: its Hello.token (None: the daemon's,
        from its token file); cookie: a Cookie header for the upgrade."""
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        lines = ["GET %s HTTP/1.1" % path, "Host: %s" % (host or "127.0.0.1:%d" % port), "Upgrade: websocket",
                 "Connection: Upgrade", "Sec-WebSocket-Key: " + key, "Sec-WebSocket-Version: 13"]
        if origin:
            lines.append("Origin: " + origin)
        if cookie:
            lines.append("Cookie: " + cookie)
        self.sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        self.buffer = b""
        while b"\r\n\r\n" not in self.buffer:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise HandshakeRefused(0, "connection closed during the upgrade")
            self.buffer += chunk
        head, _, self.buffer = self.buffer.partition(b"\r\n\r\n")
        status = int(head.split(b" ")[1])
        if status != 101:
            self.sock.settimeout(2.0)
            body = self.buffer
            try:
                while True:
                    chunk = self.sock.recv(4096)
                    if not chunk:
                        break
                    body += chunk
            except OSError:
                pass
            self.sock.close()
            raise HandshakeRefused(status, body.decode("utf-8", "replace"))
        if hello:
            self.send_json({"hello": {"protocol_version": 1, "client_name": hello,
                                      "token": access_token("http", "127.0.0.1", port) if token is None else token}})
            kind, payload = self.receive()
            assert kind == "text" and "welcome" in json.loads(payload), payload
            self.welcome = json.loads(payload)["welcome"]

    # --- sending ---
    def send_frame(self, opcode, payload, fin=True, mask=True, rsv=0):
        header = bytes([(0x80 if fin else 0) | (rsv << 4) | opcode])
        n = len(payload)
        bit = 0x80 if mask else 0
        if n < 126:
            header += bytes([bit | n])
        elif n < 65536:
            header += bytes([bit | 126]) + struct.pack(">H", n)
        else:
            header += bytes([bit | 127]) + struct.pack(">Q", n)
        if mask:
            key = os.urandom(4)
            payload = bytes(b ^ key[i % 4] for i, b in enumerate(payload)) if n < 1 << 16 else _mask_fast(payload, key)
            header += key
        self.sock.sendall(header + payload)

    def send_text(self, text):
        self.send_frame(0x1, text.encode() if isinstance(text, str) else text)

    def send_json(self, envelope):
        self.send_text(json.dumps(envelope))

    def send_binary(self, data):
        self.send_frame(0x2, data)

    # --- receiving ---
    def _read(self, n):
        while len(self.buffer) < n:
            chunk = self.sock.recv(max(65536, n - len(self.buffer)))
            if not chunk:
                raise ConnectionError("connection closed")
            self.buffer += chunk
        data, self.buffer = self.buffer[:n], self.buffer[n:]
        return data

    def receive(self):
        """The next whole message: ("text", str), ("binary", bytes) or ("close", (code, reason)).
        Pings are answered on the way."""
        opcode, message = None, b""
        while True:
            b0, b1 = self._read(2)
            fin, op, n = b0 & 0x80, b0 & 0x0F, b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            payload = self._read(n)
            if op == 0x9:  # ping
                self.send_frame(0xA, payload)
                continue
            if op == 0xA:
                continue
            if op == 0x8:
                code = struct.unpack(">H", payload[:2])[0] if len(payload) >= 2 else None
                return "close", (code, payload[2:].decode("utf-8", "replace"))
            if op != 0:
                opcode = op
            message += payload
            if fin:
                return ("text", message.decode()) if opcode == 0x1 else ("binary", message)

    def receive_json(self):
        kind, payload = self.receive()
        assert kind == "text", (kind, payload)
        return json.loads(payload)

    def receive_until(self, key, timeout=10.0):
        """The next JSON envelope holding `key`, skipping frames and others."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            kind, payload = self.receive()
            if kind == "close":
                raise ConnectionError("closed while waiting for %s: %s" % (key, payload))
            if kind == "text":
                envelope = json.loads(payload)
                if key in envelope:
                    return envelope
        raise TimeoutError("no %s within %.0f s" % (key, timeout))

    def closed_by_peer(self, timeout=5.0):
        """Whether the daemon closes the TCP connection within `timeout` (reading what comes)."""
        self.sock.settimeout(timeout)
        try:
            while self.sock.recv(65536):
                pass
            return True
        except socket.timeout:
            return False
        except OSError:  # reset
            return True
        finally:
            self.sock.settimeout(10.0)

    def close(self):
        try:
            self.sock.close()
        except OSError:
            pass


def _mask_fast(payload, key):
    import numpy as np
    data = np.frombuffer(payload, np.uint8)
    tiled = np.resize(np.frombuffer(key, np.uint8), data.size)
    return (data ^ tiled).tobytes()
