#!/usr/bin/python3
"""What the studio costs the simulation: the lockstep benchmark (the C++
client, build/bench/sim4cv_bench_client_cpp: Step -> 320x180 RGB frame in
hand, as fast as it goes) with and without a browser viewing cameras.

    /usr/bin/python3 bench/bench_studio.py [--frames 600] [--rounds 3]

One lockstep daemon on scenes/tracking/easy_urban.map with --http-port.
Viewers watch two cameras (the benchmark's own "uav" and "car_chase", or
--cameras), each
subscribed newest-frame with max_fps 30, JPEG or lossless RGB: either two
WebSocket clients that read and drop the frames (tests/studio/ws_raw.py: what
the daemon spends, alone), or headless Chromium (tools/cdp_driver.py)
showing the studio with those two views (what a browser on the same machine
adds). Rounds alternate between the set-ups; prints a Markdown table
(docs/studio.md, "What a viewer costs"): the benchmark's frames per second,
the daemon's CPU time per benchmark frame, the views' frame rates and bytes
per frame, the HTTP thread's share of a core (encoding and sending for the
viewers), and the page's decode and draw time per frame. The machine's own
load moves the frame rates by tens of per cent from run to run: compare
rows of one run, and read the CPU columns first.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path[:0] = [os.path.join(ROOT, "tools"), os.path.join(ROOT, "clients", "python"),
                os.path.join(ROOT, "tests", "studio")]

from sim4cv.daemon import OwnDaemon  # noqa: E402
from ws_raw import RawWebSocket  # noqa: E402

CLIENT = os.path.join(ROOT, "build", "bench", "sim4cv_bench_client_cpp")
MAP = os.path.join(ROOT, "scenes", "tracking", "easy_urban.map")


def cpu_seconds(pid, tid=None):
    path = "/proc/%d/stat" % pid if tid is None else "/proc/%d/task/%d/stat" % (pid, tid)
    fields = open(path).read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def http_thread(pid):
    """The HTTP transport's thread: the daemon starts it last, after the sim
    thread (and the renderer's worker threads) and the TCP thread."""
    return max(int(tid) for tid in os.listdir("/proc/%d/task" % pid))


def bench(daemon, frames):
    before = cpu_seconds(daemon.proc.pid)
    http_before = cpu_seconds(daemon.proc.pid, daemon.http_tid)
    started = time.monotonic()
    run = subprocess.run([CLIENT, "--address", daemon.address, "--frames", str(frames)], capture_output=True,
                         text=True)
    if run.returncode != 0:
        sys.exit("%s failed (%d): %s" % (CLIENT, run.returncode, run.stderr.strip()))
    out = run.stdout
    result = json.loads(out.strip().splitlines()[-1])
    result["daemon_cpu_ms_per_frame"] = (cpu_seconds(daemon.proc.pid) - before) * 1000 / frames
    result["http_cpu_share"] = (cpu_seconds(daemon.proc.pid, daemon.http_tid) - http_before) / (
        time.monotonic() - started)
    return result


class SocketViewers:
    """Two WebSocket viewers that read every frame sent and drop it."""

    def __init__(self, port, query, cameras):
        self.stop = False
        self.counts = []
        self.threads = []
        for camera in cameras:
            ws = RawWebSocket(port, path="/ws?" + query, hello="bench-" + camera)
            ws.send_json({"subscribe": {"camera": camera, "channels": ["CHANNEL_RGB"],
                                        "delivery": "DELIVERY_NEWEST", "max_fps": 30}})
            ws.receive_until("subscribed")
            count = [0, 0]
            self.counts.append(count)
            thread = threading.Thread(target=self.read, args=(ws, count), daemon=True)
            thread.start()
            self.threads.append((thread, ws))

    def read(self, ws, count):
        ws.sock.settimeout(None)
        while not self.stop:
            try:
                kind, payload = ws.receive()
            except OSError:  # closed by close()
                return
            if kind == "binary":
                count[0] += 1
                count[1] += len(payload)

    def reset(self):
        for count in self.counts:
            count[:] = [0, 0]

    def shown(self):
        return [(frames, size, 0.0) for frames, size in self.counts]

    def close(self):
        self.stop = True
        for _, ws in self.threads:
            ws.close()


class BrowserViewers:
    """The studio in Chromium with the two views."""

    def __init__(self, browser, port, query, cameras):
        views = "&".join("view=%s:rgb" % camera for camera in cameras)
        self.page = browser.new_page("http://127.0.0.1:%d/?%s&%s" % (port, views, query))
        self.page.wait_for("window.studio && studio.ready && studio.views.length === 2 && "
                           "studio.views.every(v => v.stats.textContent.startsWith('subscribed'))", 60)

    def reset(self):
        self.page.evaluate("studio.views.forEach(v => { v.frames = 0; v.bytes = 0; v.drawMs = 0; })")

    def shown(self):
        return self.page.evaluate("studio.views.map(v => [v.frames, v.bytes, v.drawMs])")

    def close(self):
        self.page.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-browser", action="store_true", help="only the WebSocket viewers")
    parser.add_argument("--cameras", default="uav,car_chase",
                        help="the two views' cameras (uav,uav: no camera rendered for the viewers alone)")
    args = parser.parse_args()
    cameras = args.cameras.split(",")
    setups = [("none", None, None),
              ("2 WebSocket viewers, JPEG", "sockets", "rgb=jpeg"),
              ("2 WebSocket viewers, lossless", "sockets", "rgb=raw")]
    if not args.no_browser:
        setups += [("Chromium, 2 views, JPEG", "browser", "rgb=jpeg"),
                   ("Chromium, 2 views, lossless", "browser", "rgb=raw")]
    results = {name: [] for name, _, _ in setups}
    views = {name: [] for name, _, _ in setups}
    browser = None
    if not args.no_browser:
        from cdp_driver import Browser  # python3-websocket and Chromium: only for the browser rows
        browser = Browser()
    try:
        with OwnDaemon(["--map", MAP, "--http-port", "0", "--udp-port", "-1", "--log-level", "warning"]) as daemon:
            port = int(daemon.fields["http"])
            daemon.http_tid = http_thread(daemon.proc.pid)
            bench(daemon, 100)  # warm
            for _ in range(args.rounds):
                for name, kind, query in setups:
                    viewers = None
                    if kind == "sockets":
                        viewers = SocketViewers(port, query, cameras)
                    elif kind == "browser":
                        viewers = BrowserViewers(browser, port, query, cameras)
                    if viewers:
                        time.sleep(1.0)
                        viewers.reset()
                    started = time.monotonic()
                    results[name].append(bench(daemon, args.frames))
                    seconds = time.monotonic() - started
                    if viewers:
                        views[name].append([(f / seconds, b / max(f, 1), d / max(f, 1)) for f, b, d in viewers.shown()])
                        viewers.close()
    finally:
        if browser:
            browser.close()
    base = statistics.median(r["fps"] for r in results["none"])
    print("| viewers | lockstep fps (median of %d) | change | daemon CPU / frame | HTTP thread's CPU | views' fps |"
          " bytes / view frame | page's decode+draw / frame |" % args.rounds)
    print("|---|---|---|---|---|---|---|---|")
    for name, kind, _ in setups:
        fps = statistics.median(r["fps"] for r in results[name])
        cpu = statistics.median(r["daemon_cpu_ms_per_frame"] for r in results[name])
        http = statistics.median(r["http_cpu_share"] for r in results[name])
        row = "| %s | %.0f | %+.1f%% | %.2f ms | %.1f%% |" % (name, fps, 100 * (fps / base - 1), cpu, 100 * http)
        if views[name]:
            per_view = list(zip(*views[name]))
            row += " %s | %s | %s |" % (
                " / ".join("%.0f" % statistics.median(v[0] for v in view) for view in per_view),
                " / ".join("%.0f KB" % (statistics.median(v[1] for v in view) / 1000) for view in per_view),
                " / ".join("%.2f ms" % statistics.median(v[2] for v in view) for view in per_view)
                if kind == "browser" else "–")
        else:
            row += " – | – | – |"
        print(row)


if __name__ == "__main__":
    main()
