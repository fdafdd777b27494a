"""A small Chrome DevTools Protocol driver of our own, for the studio's
browser tests (tests/studio) and its screenshots (tools/studio_screenshots.py):
starts Debian's Chromium headless with a throw-away profile, opens pages,
evaluates JavaScript, sends mouse events, takes screenshots, and records
console errors and uncaught exceptions.

    with Browser() as browser:
        page = browser.new_page("http://127.0.0.1:8080/")
        page.wait_for("window.studio && window.studio.ready")
        page.evaluate("document.title")
        page.screenshot("out.png")
        assert not page.problems            # console errors, exceptions

Only the standard library and python3-websocket (Debian's websocket-client).
"""

import base64
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import threading
import time

import websocket  # python3-websocket

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


def chromium_path():
    """The Chromium binary ($CHROMIUM, else the first on PATH), or None."""
    if os.environ.get("CHROMIUM"):
        return os.environ["CHROMIUM"]
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class CdpError(RuntimeError):
    """A DevTools command failed, a page threw, or a wait timed out."""


class Browser:
    """Headless Chromium and its DevTools connection (browser-level)."""

    def __init__(self, width=1400, height=900, startup_s=30.0):
        path = chromium_path()
        if path is None:
            raise CdpError("Chromium not found (install Debian's chromium, or set CHROMIUM)")
        self.profile = tempfile.mkdtemp(prefix="sim4cv-chromium-")
        self.proc = subprocess.Popen(
            [path, "--headless=new", "--remote-debugging-port=0", "--user-data-dir=" + self.profile,
             "--no-first-run", "--no-default-browser-check", "--disable-gpu", "--no-sandbox",
             "--disable-extensions", "--disable-background-networking", "--disable-dev-shm-usage",
             "--window-size=%d,%d" % (width, height), "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        self.width, self.height = width, height
        self._stderr = []
        threading.Thread(target=self._drain, daemon=True).start()
        # Chromium writes its chosen port into the profile once it listens.
        port_file = os.path.join(self.profile, "DevToolsActivePort")
        deadline = time.monotonic() + startup_s
        while True:
            if os.path.exists(port_file):
                lines = open(port_file).read().split("\n")
                if len(lines) >= 2 and lines[0].strip():
                    break
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.close()
                raise CdpError("Chromium did not start: %s" % "\n".join(self._stderr[-10:]))
            time.sleep(0.05)
        self.url = "ws://127.0.0.1:%s%s" % (lines[0].strip(), lines[1].strip())
        self._ws = websocket.create_connection(self.url, timeout=startup_s, suppress_origin=True)
        self._ws.settimeout(None)  # the reader thread waits for events as long as the browser lives
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._answers = {}
        self._events = []  # (sessionId, method, params)
        self._cond = threading.Condition(self._lock)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _drain(self):
        for line in self.proc.stderr:
            self._stderr.append(line.decode("utf-8", "replace").rstrip())
            del self._stderr[:-200]

    def _read(self):
        while True:
            try:
                message = json.loads(self._ws.recv())
            except Exception:  # closed
                with self._cond:
                    self._answers[None] = None
                    self._cond.notify_all()
                return
            with self._cond:
                if "id" in message:
                    self._answers[message["id"]] = message
                else:
                    self._events.append((message.get("sessionId"), message["method"], message.get("params", {})))
                self._cond.notify_all()

    def send(self, method, params=None, session=None, timeout=30.0):
        """One DevTools command; its result, or CdpError with the protocol's message."""
        command_id = next(self._ids)
        message = {"id": command_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        self._ws.send(json.dumps(message))
        deadline = time.monotonic() + timeout
        with self._cond:
            while command_id not in self._answers:
                if None in self._answers:
                    raise CdpError("DevTools connection closed during %s" % method)
                left = deadline - time.monotonic()
                if left <= 0:
                    raise CdpError("%s: no answer within %.0f s" % (method, timeout))
                self._cond.wait(left)
            answer = self._answers.pop(command_id)
        if "error" in answer:
            raise CdpError("%s: %s" % (method, answer["error"].get("message")))
        return answer.get("result", {})

    def events(self, session):
        """Takes the events recorded for `session` so far."""
        with self._cond:
            mine = [(m, p) for s, m, p in self._events if s == session]
            self._events = [e for e in self._events if e[0] != session]
        return mine

    def new_page(self, url, timeout=30.0):
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        page = Page(self, target, session)
        page.send("Runtime.enable")
        page.send("Log.enable")
        page.send("Page.enable")
        page.send("Emulation.setDeviceMetricsOverride",
                  {"width": self.width, "height": self.height, "deviceScaleFactor": 1, "mobile": False})
        page.navigate(url, timeout)
        return page

    def close(self):
        try:
            if getattr(self, "_ws", None):
                try:
                    self.send("Browser.close", timeout=5.0)
                except CdpError:
                    pass
                self._ws.close()
        finally:
            if self.proc.poll() is None:
                try:
                    self.proc.wait(5)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
            shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Page:
    """One tab, attached in flat mode (commands carry its session id)."""

    def __init__(self, browser, target, session):
        self.browser, self.target, self.session = browser, target, session
        self.problems = []  # console errors, exceptions, failed loads: what a test says must not happen
        self.console = []

    def send(self, method, params=None, timeout=30.0):
        return self.browser.send(method, params, self.session, timeout)

    def collect(self):
        """Files the page's new console messages and exceptions."""
        for method, params in self.browser.events(self.session):
            if method == "Runtime.exceptionThrown":
                details = params["exceptionDetails"]
                text = details.get("exception", {}).get("description") or details.get("text")
                self.problems.append("exception: %s" % text)
            elif method == "Runtime.consoleAPICalled":
                text = " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", []))
                self.console.append((params["type"], text))
                if params["type"] in ("error", "assert"):
                    self.problems.append("console.%s: %s" % (params["type"], text))
            elif method == "Log.entryAdded":
                entry = params["entry"]
                if entry.get("level") == "error":
                    self.problems.append("log: %s %s" % (entry.get("text"), entry.get("url", "")))

    def navigate(self, url, timeout=30.0):
        self.send("Page.navigate", {"url": url})
        self.wait_for("document.readyState === 'complete'", timeout)

    def evaluate(self, expression, timeout=30.0):
        """The value of a JavaScript expression (promises awaited), as JSON."""
        result = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                                "awaitPromise": True}, timeout)
        self.collect()
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            raise CdpError("%s threw: %s" % (expression[:80], details.get("exception", {}).get("description")
                                             or details.get("text")))
        return result["result"].get("value")

    def wait_for(self, expression, timeout=30.0, poll_s=0.05):
        """Waits until a JavaScript expression is truthy; its value."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                value = self.evaluate(expression)
            except CdpError:
                value = None
            if value:
                return value
            if time.monotonic() > deadline:
                raise CdpError("waited %.0f s for: %s (page problems: %s)" % (timeout, expression, self.problems))
            time.sleep(poll_s)

    def click(self, x, y):
        """A left click at page coordinates (CSS pixels)."""
        for kind in ("mouseMoved", "mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left",
                                                   "clickCount": 1 if kind != "mouseMoved" else 0})

    # key -> (KeyboardEvent.code, Windows virtual key code) for keys with no text.
    KEYS = {"ArrowLeft": ("ArrowLeft", 37), "ArrowUp": ("ArrowUp", 38), "ArrowRight": ("ArrowRight", 39),
            "ArrowDown": ("ArrowDown", 40), "Escape": ("Escape", 27), "Enter": ("Enter", 13), " ": ("Space", 32)}

    def key(self, key, down=True):
        """A real key press (down=True) or release at the focused element, as
        DevTools' Input.dispatchKeyEvent sends it: `key` is KeyboardEvent.key
        ("w", "ArrowLeft", " "); a held key is a keyDown now and a keyUp later."""
        if key in self.KEYS:
            code, key_code = self.KEYS[key]
        else:
            code, key_code = "Key" + key.upper(), ord(key.upper())
        params = {"type": "keyDown" if down else "keyUp", "key": key, "code": code,
                  "windowsVirtualKeyCode": key_code, "nativeVirtualKeyCode": key_code}
        if down and len(key) == 1:
            params["text"] = key
        self.send("Input.dispatchKeyEvent", params)

    def drag(self, x0, y0, x1, y1, steps=8):
        """A left-button drag from (x0, y0) to (x1, y1), page coordinates: pressed, moved in
        `steps` steps with the button held, released (pointer events follow, as for a person)."""
        mouse = {"button": "left", "buttons": 1, "clickCount": 1}
        self.send("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": x0, "y": y0})
        self.send("Input.dispatchMouseEvent", dict(mouse, type="mousePressed", x=x0, y=y0))
        for k in range(1, steps + 1):
            self.send("Input.dispatchMouseEvent", {"type": "mouseMoved", "button": "left", "buttons": 1,
                                                   "x": x0 + (x1 - x0) * k / steps, "y": y0 + (y1 - y0) * k / steps})
        self.send("Input.dispatchMouseEvent", dict(mouse, type="mouseReleased", x=x1, y=y1, buttons=0))

    def screenshot(self, path, clip=None):
        """A PNG of the page (or of `clip`: {x, y, width, height}) written to `path`."""
        params = {"format": "png"}
        if clip:
            params["clip"] = dict(clip, scale=1)
        data = self.send("Page.captureScreenshot", params)["data"]
        with open(path, "wb") as out:
            out.write(base64.b64decode(data))
        return path

    def close(self):
        self.browser.send("Target.closeTarget", {"targetId": self.target})
