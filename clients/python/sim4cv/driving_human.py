"""A person drives the car with the keyboard, scored like the network
(docs/driving.md, "Human driving"): the paper compares its network with
people driving the test maps.

    python3 -m sim4cv.driving human --map scenes/driving/test/01_desert.map --out DIR [--camera car_front|car_chase]

A realtime sim4cvd of its own runs the map (or --address connects to one
already running: frames over TCP or shm, controls over UDP); an OpenCV
window shows the camera with the speed, the distance to the lane centre and
the lap's progress. Keys (window focused): arrows or W/A/S/D, space brakes,
Q or Esc ends the run. The run stops after one lap (or --seconds) and
DIR/driving.json holds the same score as `sim4cv.driving evaluate`
(policy "human"), DIR/runs/<map>_<route>.csv the trajectory.

Keyboard input has no key-up events in an OpenCV window: a key counts as
held while its auto-repeat keeps arriving (KEY_HOLD_S), so steering and
throttle ramp while a key is held and return when it is released.
"""

import json
import math
import os
import time
from typing import Dict, List, Optional

from . import driving_metrics as dm
from .driving_dataset import RoutePath, parse_map

KEY_HOLD_S = 0.25          # a key's auto-repeat must arrive within this to count as held
STEER_RATE = 2.5           # steering units per second while an arrow is held (full lock in 0.4 s)
CENTRE_RATE = 4.0          # back towards 0 when no arrow is held
KEYS = {"left": (81, 2424832, ord("a")), "right": (83, 2555904, ord("d")), "up": (82, 2490368, ord("w")),
        "down": (84, 2621440, ord("s")), "brake": (32,), "quit": (27, ord("q"))}


class KeyboardDriver:
    """Turns key presses (with times) into smooth Controls. `press(code, t)`
    records a key; `controls(frame, pose, speed)` advances to the frame's
    time. Without a window (tests), keys are fed with press()."""

    def __init__(self, window: Optional[str] = None, speed_cap: float = 20.0):
        self.window = window
        self.speed_cap = speed_cap
        self.last: Dict[str, float] = {}
        self.steering = 0.0
        self.t = None
        self.done = False
        self.status = ""

    def press(self, code: int, t: float) -> None:
        for name, codes in KEYS.items():
            if code in codes:
                self.last[name] = t
                if name == "quit":
                    self.done = True

    def held(self, name: str, t: float) -> bool:
        return t - self.last.get(name, -1e9) <= KEY_HOLD_S

    def step(self, t: float) -> tuple:
        """(steering, throttle, brake) at time t (s)."""
        dt = 0.0 if self.t is None else max(t - self.t, 0.0)
        self.t = t
        target = (1.0 if self.held("right", t) else 0.0) - (1.0 if self.held("left", t) else 0.0)
        rate = STEER_RATE if target else CENTRE_RATE
        delta = target - self.steering
        self.steering += max(-rate * dt, min(rate * dt, delta))
        throttle = 1.0 if self.held("up", t) else 0.0
        brake = 1.0 if self.held("brake", t) or self.held("down", t) else 0.0
        return self.steering, throttle, brake

    def controls(self, frame, pose, speed):
        now = time.monotonic()
        if self.window:
            self._show(frame, speed, now)
        steering, throttle, brake = self.step(now)
        if speed >= self.speed_cap:
            throttle = 0.0
        return steering, throttle, brake

    def _show(self, frame, speed, now):
        import cv2
        image = cv2.cvtColor(frame.image("rgb"), cv2.COLOR_RGB2BGR)
        image = cv2.resize(image, (image.shape[1] * 2, image.shape[0] * 2), interpolation=cv2.INTER_LINEAR)
        cv2.putText(image, "%.1f m/s  %s" % (speed, self.status), (10, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.6,
                    (255, 255, 255), 2)
        cv2.imshow(self.window, image)
        code = cv2.waitKeyEx(1)
        while code != -1:
            self.press(code, now)
            code = cv2.waitKeyEx(1)


class Scorer:
    """Records the car against its route's ideal path, frame by frame, as the evaluation does."""

    def __init__(self, map_path: str, route: Optional[str] = None, laps: float = 1.0):
        self.info = parse_map(map_path)
        self.route = route or next(iter(self.info["routes"]))
        self.path = RoutePath(self.info, self.route)
        self.lap = self.path.length * laps
        self.progress = None
        self.collisions = dm.Collisions(self.info["objects"])
        self.rows: List[list] = []
        self.deviations: List[float] = []
        self.t0 = None
        self.driver = None  # whose status line shows the score, and whose `done` ends the lap

    def __call__(self, frame, pose):
        x, y, yaw = pose
        if self.progress is None:
            self.progress = dm.Progress(self.path, dm.nearest_u(self.path, x, y))
            self.start_u = self.progress.u
            self.t0 = frame.sim_time
        d = self.progress.update(x, y)
        hit = self.collisions.update(x, y, yaw)
        self.deviations.append(d)
        done_m = self.progress.u - self.start_u
        self.rows.append([round(frame.sim_time - self.t0, 4), round(x, 3), round(y, 3), round(math.degrees(yaw), 2),
                          round(self.progress.u, 3), round(d, 4), "", "", "", "", hit])
        if self.driver is not None:
            self.driver.status = "lane %+.2f m  lap %.0f%%" % (d, 100.0 * done_m / self.lap)
            if done_m >= self.lap:
                self.driver.done = True

    def report(self, out: str, name: str = "human") -> dict:
        from .driving_eval import _write_rows
        os.makedirs(os.path.join(out, "runs"), exist_ok=True)
        done_m = (self.progress.u - self.start_u) if self.progress else 0.0
        run = dm.score(self.deviations, max(min(done_m, self.lap), 0.0), self.collisions.count)
        run.update(completed=done_m >= self.lap, route=self.route, lap_m=round(self.lap, 2),
                   sim_seconds=self.rows[-1][0] if self.rows else 0.0)
        map_name = self.info["name"]
        _write_rows(os.path.join(out, "runs", "%s_%s.csv" % (map_name, self.route)), self.rows)
        report = {"settings": {"policy": "human", "driver": name, "maps": [map_name]},
                  "maps": {map_name: {"surroundings": self.info["surroundings"], "routes": {self.route: run},
                                      "score": dm.pooled([run], [self.deviations])}},
                  "overall": dm.pooled([run], [self.deviations]),
                  "histogram": {"overall": dm.cumulative_histogram(self.deviations)[1]},
                  "histogram_edges_m": dm.cumulative_histogram([])[0], "paper": dm.PAPER}
        with open(os.path.join(out, "driving.json"), "w") as f:
            json.dump(report, f, indent=1)
        return report
