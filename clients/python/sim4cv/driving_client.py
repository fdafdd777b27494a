"""The Python driving client of the driving case study (docs/driving.md,
"Driving clients"): frames of the car's first-person camera arrive over
shared memory or TCP, the policy (the trained network by PyTorch or OpenCV,
or the reference policy) turns each into waypoints, the controller into
Controls, which go back over UDP every frame.

    python3 -m sim4cv.driving drive --model model.pt --frames shm://drive --controls udp://127.0.0.1:PORT
    python3 -m sim4cv.driving drive --reference MAP --frames tcp://127.0.0.1:PORT --lockstep

Realtime (default): the newest frame is taken (frames the client was too
slow for are skipped), controls go over --controls. --lockstep: this client
steps the world, and controls go over the frames connection, so they are
applied before the next step (over UDP they could reach the daemon after
the Step that should follow them).

Lane change: type `left` or `right` (then Enter) on stdin at any time, or
give --switch-every S: the left lane is driven by mirroring the image and
the predicted h (driving_eval.NetworkPolicy's lane trick).
"""

import sys
import threading
import time
from typing import Optional

from . import driving_control as dc
from . import driving_eval as de
from . import driving_metrics as dm
from .driving_dataset import RoutePath, parse_map


class Lane:
    """The lane the client drives, switched from stdin or a timer."""

    def __init__(self, lane: str = "right", switch_every: float = 0.0):
        self.lane = lane
        self.switch_every = switch_every
        self.switched_at = None

    def tick(self, sim_time: float) -> str:
        if self.switch_every > 0:
            if self.switched_at is None:
                self.switched_at = sim_time
            elif sim_time - self.switched_at >= self.switch_every:
                self.lane = "left" if self.lane == "right" else "right"
                self.switched_at = sim_time
        return self.lane

    def listen(self, stream=None) -> None:
        """Reads `left` / `right` lines from stream (stdin) in a daemon thread."""
        stream = stream or sys.stdin

        def read():
            for line in stream:
                word = line.strip().lower()
                if word in ("left", "right", "l", "r"):
                    self.lane = "left" if word.startswith("l") else "right"
        threading.Thread(target=read, daemon=True).start()


class ReferenceDriver:
    """The reference policy for a client that does not own the route: the
    map file gives the route (the car's nearest one), the frame the car's pose."""

    LANE_SHIFT_PER_CALL_M = 0.04  # how fast the aimed-at lane moves sideways (1.2 m/s at 30 Hz)

    def __init__(self, map_path: str, route: Optional[str] = None):
        info = parse_map(map_path)
        self.path = RoutePath(info, route or next(iter(info["routes"])))
        self.progress = None
        self.policy = de.ReferencePolicy()
        self.shift = None  # m left of the right lane's centre that the car aims at

    def waypoints(self, rgb, pose, lane: str):
        if self.progress is None:
            self.progress = dm.Progress(self.path, dm.nearest_u(self.path, pose[0], pose[1]))
        deviation = self.progress.update(pose[0], pose[1])
        w = self.policy.waypoints(rgb, pose, self.progress)
        # the left lane's centre is 4 m left of the right lane's; the aim moves
        # there gradually: jumping 4 m sideways 2 m ahead would be full lock
        target = 4.0 if lane == "left" else 0.0
        if self.shift is None:
            self.shift = min(max(-deviation, 0.0), 4.0)
        step = self.LANE_SHIFT_PER_CALL_M
        self.shift += min(max(target - self.shift, -step), step)
        return [v if i % 2 == 0 else v - self.shift for i, v in enumerate(w)]


def drive(frames_address: str, controls_address: Optional[str], policy, car: str = "car",
          camera: str = "car_front", speed: float = de.DEFAULT_SPEED, lockstep: bool = False,
          seconds: float = 0.0, frames: int = 0, lane: Optional[Lane] = None, log=print, recorder=None,
          controller: dc.Controller = dc.Controller()) -> dict:
    """Drives until `seconds` of simulated time or `frames` frames (0: for ever),
    or until the policy's `done` turns true; returns counts: frames, skipped,
    policy_ms (mean), fps, age_ms (mean frame age at decision).

    A policy has waypoints(rgb, pose, lane_or_progress) (the controller makes
    the Controls) or controls(frame, pose, speed) -> (steering, throttle,
    brake) (e.g. a person at the keyboard). recorder(frame, pose), if given,
    sees every frame's (x, y, yaw) of the car. controller: how waypoints become
    Controls (the model card's settings, from `drive`)."""
    import sim4cv
    lane = lane or Lane()
    with sim4cv.connect(frames_address, name="driving_client", timeout=30.0) as source:
        car_id = next((e.id for e in source.get_world().entities if e.name == car), None)
        if car_id is None:
            raise de.EvalError("no entity called %r in the world (--car)" % car)
        sink = source if lockstep or not controls_address else sim4cv.connect(controls_address, name="driving_controls",
                                                                                timeout=10.0)
        try:
            source.subscribe(camera, ["rgb"], "lockstep" if lockstep else "newest", with_state=True)
            return _loop(source, sink, car_id, policy, speed, lockstep, seconds, frames, lane, log, recorder,
                         controller)
        finally:
            if sink is not source:
                sink.close()


def _loop(source, sink, car_id, policy, speed, lockstep, seconds, frames, lane, log, recorder, controller):
    counts = {"frames": 0, "skipped": 0, "policy_s": 0.0, "age_ns": 0}
    last_id, t_start, t_report, start_sim = None, time.monotonic(), time.monotonic(), None
    while True:
        frame = source.step_and_receive(timeout=30.0) if lockstep else source.receive_frame(timeout=30.0)
        if start_sim is None:
            start_sim = frame.sim_time
        if last_id is not None and frame.frame_id > last_id + 1:
            counts["skipped"] += frame.frame_id - last_id - 1
        last_id = frame.frame_id
        pose = de.car_pose(frame, car_id)
        if pose is None:
            raise de.EvalError("the frame's state holds no car %d: was it removed?" % car_id)
        x, y, yaw, car_speed = pose
        if recorder is not None:
            recorder(frame, (x, y, yaw))
        started = time.perf_counter()
        side = lane.tick(frame.sim_time)
        if hasattr(policy, "controls"):
            steering, throttle, brake = policy.controls(frame, (x, y, yaw), car_speed)
        else:
            if isinstance(policy, ReferenceDriver):
                w = policy.waypoints(frame.image("rgb"), (x, y, yaw), side)
            else:
                policy.lane = side
                w = policy.waypoints(frame.image("rgb"), (x, y, yaw), None)
            de.check_waypoints(w, policy, "frame %d" % frame.frame_id)
            steering, throttle, brake = controller.controls(w, speed=car_speed, max_speed=speed)
        counts["policy_s"] += time.perf_counter() - started
        counts["age_ns"] += time.monotonic_ns() - frame.render_end_mono_ns
        sink.send_controls(car_id, steering, throttle, brake)
        counts["frames"] += 1
        now = time.monotonic()
        if now - t_report >= 1.0:
            log("%d frames, %.1f fps, policy %.2f ms, lane %s, speed %.1f m/s"
                % (counts["frames"], counts["frames"] / (now - t_start),
                   1000 * counts["policy_s"] / counts["frames"], side, car_speed))
            t_report = now
        if (seconds and frame.sim_time - start_sim >= seconds) or (frames and counts["frames"] >= frames) \
                or getattr(policy, "done", False):
            break
    n = max(counts["frames"], 1)
    return {"frames": counts["frames"], "skipped": counts["skipped"],
            "policy_ms": round(1000 * counts["policy_s"] / n, 3),
            "fps": round(counts["frames"] / max(time.monotonic() - t_start, 1e-9), 2),
            "age_ms": round(counts["age_ns"] / n / 1e6, 3)}
