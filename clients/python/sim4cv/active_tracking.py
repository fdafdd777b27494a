"""Active object tracking as a reinforcement-learning environment, Gymnasium style.

    from sim4cv.active_tracking import ActiveTrackingEnv
    with ActiveTrackingEnv(map="easy_desert", car_speed=6) as env:   # starts its own sim4cvd
        obs, info = env.reset(seed=0)
        for _ in range(300):
            action = env.expert_action(info)          # or env.action_space.sample(), or your policy(obs)
            obs, reward, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                obs, info = env.reset()

The agent flies the UAV from its camera's images (docs/tracking.md, "Active
tracking"). `ActiveTrackingEnv` subclasses `gymnasium.Env` when gymnasium
imports, and is otherwise a plain class with the same API; its spaces are
`gymnasium.spaces.Box` or, without gymnasium, the stand-in `Box` below.

Observation: the RGB image of the UAV's camera, (H, W, 3) uint8 (320 x 180
unless width/height say otherwise), optionally downscaled by a whole factor
(`downscale`: mean of k x k blocks).

Action: (forward m/s, sideways m/s, yaw rate deg/s) in the UAV's heading
frame: forward along its heading, sideways positive to its left, yaw rate
positive counter-clockwise (a left turn); bounded by `max_speed` (8 m/s) and
`max_yaw_rate` (90 deg/s), clipped to them. Each frame the env turns it into
the world-frame order uav_velocity(vx, vy, 0, yaw_rate) with the UAV's
current heading psi: vx = f cos psi - s sin psi, vy = f sin psi + s cos psi
(vertical velocity 0: the UAV keeps its altitude).

Step: one env step is `frame_skip` lockstep frames (step_and_receive), the
order renewed with the new heading before each of them.

Reward, per frame, from the ground truth of the frame (its state, sent with
with_state=True): d = the horizontal distance from the UAV's centre to the
target's centre, angle = the bearing of the target relative to the UAV's
heading (degrees in (-180, 180], positive to the left),

    r = clip(1 - |d - d_star| / d_max - |angle| / angle_max, -1, 1)

(the form of Luo et al., "End-to-end active object tracking via
reinforcement learning", ICML 2018). d_star (`target_distance`) defaults to
the distance at which the camera's optical axis meets the target: the UAV's
height above the target's centre / tan(camera pitch), both measured on the
first frame of the episode (15 m / tan 60 deg = 8.66 m in the shipped scenes,
where the follow order stations the UAV exactly there); d_max
(`max_distance`) defaults to 3 d_star, angle_max (`max_angle`) to 90 deg.
A step's reward is the mean of its frames' rewards, so it lies in [-1, 1].

terminated: the target is lost: it has had no box (no visible pixel) in
`lost_frames` (30) consecutive frames, or d > d_max, or the target is gone
from the world. truncated: `max_steps` (1000) steps were taken.

reset(seed=None, options=None): Configure Reset (the world back to its start:
time 0, the car at its start, the UAV above and behind it), then
  1. car speed: options["car_speed"], else a draw from `car_speed_range`
     (uniform, from the env's seeded np_random), else unchanged (the scene's
     6 m/s or the daemon's --car-speed);
  2. `warmup_frames` (30) frames of uav_follow(uav, car): the UAV films the
     car from behind (the scene's own order, re-given);
  3. the start offset: `start_frames` (15) frames in which the UAV flies the
     target's velocity plus a random heading-frame velocity, uniform in
     +-start_jitter = (forward m/s, sideways m/s, yaw deg/s), default
     (2, 2, 20) (options["start_jitter"] overrides; (0, 0, 0) or
     start_frames 0: no offset);
  4. then the agent has control; the last frame's image is the first
     observation.
The lockstep daemon is deterministic, so reset(seed=s) gives the same first
observation and the same episode for the same actions every time.

info: frame_id, sim_time, box (the target's ground-truth sim4cv.Box, None
when not visible), distance (d), angle, target_distance (d_star),
max_distance, lost_frames (consecutive frames without a box), uav_position,
target_position, heading_deg (the UAV's), target_velocity (the target's
velocity in the UAV's heading frame: forward, left; m/s), step.
"""

import math
import os

import numpy as np

import sim4cv
from sim4cv.daemon import REPO_ROOT, OwnDaemon
from sim4cv.env_base import Box, SimEnv, box  # noqa: F401 (Box: re-exported)


MAPS_DIR = os.path.join(REPO_ROOT, "scenes")


class ActiveTrackingError(RuntimeError):
    """The environment could not start or talk to its daemon."""




# ----------------------------------------------------------------------------- the daemon


def map_path(name):
    """"easy_desert", "tracking/easy_desert" or a path to a .map file -> the file."""
    if name.endswith(".map"):
        return os.path.abspath(name)
    if "/" not in name:
        name = "tracking/" + name
    return os.path.join(MAPS_DIR, name + ".map")


# ----------------------------------------------------------------------------- geometry


def _heading_deg(q):
    """Heading (degrees, 0 = east, counter-clockwise) of a body->world quaternion (w, x, y, z)."""
    w, x, y, z = q
    return math.degrees(math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


def _pitch_down_deg(q):
    """How far below the horizon a camera with OpenCV's axes (z forward) looks."""
    w, x, y, z = q
    forward_z = 1.0 - 2.0 * (x * x + y * y)  # the world z of the camera's z axis
    return math.degrees(math.asin(max(-1.0, min(1.0, -forward_z))))


def _wrap_deg(a):
    a = math.fmod(a + 180.0, 360.0)
    if a <= 0.0:
        a += 360.0
    return a - 180.0


def _to_heading_frame(vx, vy, heading_deg):
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    return vx * c + vy * s, -vx * s + vy * c


def _to_world(forward, sideways, heading_deg):
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    return forward * c - sideways * s, forward * s + sideways * c


# ----------------------------------------------------------------------------- the environment


class ActiveTrackingEnv(SimEnv):
    """Fly the UAV by heading-frame velocity commands from its camera's
    images and keep the target car straight ahead at the ideal distance.
    See the module's docstring (and docs/tracking.md, "Active tracking") for
    the observation, action, reward and episode rules.

    Arguments: address (any sim4cv.connect address of a lockstep daemon;
    None: start an own sim4cvd, killed by close()); map ("easy_desert",
    "tracking/hard_urban" or a .map path; None: the default scene; with
    `address` it is loaded with LoadMap); car_speed (the own daemon's
    --car-speed / LoadMap's car speed; None: 6 m/s); width, height (the own
    daemon's camera size); daemon_args (more sim4cvd flags); camera ("uav");
    downscale (a whole factor); frame_skip; max_steps; lost_frames;
    target_distance (d*, None: from the camera), max_distance (d_max, None:
    3 d*), max_angle (deg); max_speed (m/s), max_yaw_rate (deg/s);
    warmup_frames, start_frames, start_jitter, car_speed_range (reset, see
    the module's docstring); timeout (s, per request).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, address=None, map=None, car_speed=None, width=320, height=180, daemon_args=(),
                 camera="uav", downscale=1, frame_skip=1, max_steps=1000, lost_frames=30,
                 target_distance=None, max_distance=None, max_angle=90.0, max_speed=8.0, max_yaw_rate=90.0,
                 warmup_frames=30, start_frames=15, start_jitter=(2.0, 2.0, 20.0), car_speed_range=None,
                 render_mode="rgb_array", timeout=30.0, name="sim4cv.active_tracking"):
        if int(downscale) < 1 or int(frame_skip) < 1:
            raise ValueError("downscale and frame_skip must be whole numbers >= 1")
        self.render_mode = render_mode
        self.camera = camera
        self.downscale = int(downscale)
        self.frame_skip = int(frame_skip)
        self.max_steps = int(max_steps)
        self.lost_frames = int(lost_frames)
        self.target_distance_setting = target_distance
        self.max_distance_setting = max_distance
        self.max_angle = float(max_angle)
        self.max_speed = float(max_speed)
        self.max_yaw_rate = float(max_yaw_rate)
        self.warmup_frames = int(warmup_frames)
        self.start_frames = int(start_frames)
        self.start_jitter = tuple(float(v) for v in start_jitter) if start_jitter else (0.0, 0.0, 0.0)
        self.car_speed_range = car_speed_range
        self.timeout = float(timeout)
        self.daemon = None
        self.client = None
        self._closed = False

        try:
            if address is None:
                args = ["--width", str(int(width)), "--height", str(int(height))]
                if map is not None:
                    args += ["--map", map_path(map)]
                if car_speed is not None:
                    args += ["--car-speed", repr(float(car_speed))]
                self.daemon = OwnDaemon(args + list(daemon_args))  # lockstep
                address = self.daemon.address
            self.address = address
            self.client = sim4cv.connect(address, name=name, timeout=self.timeout)
            if self.client.welcome.mode != sim4cv.SIM_MODE_LOCKSTEP:
                raise ActiveTrackingError("%s does not run in lockstep mode (start sim4cvd with --mode lockstep)"
                                          % address)
            if self.daemon is None and map is not None:
                if map.endswith(".map"):
                    with open(map, encoding="utf-8") as f:
                        self.client.load_map_text(f.read(), car_speed=float(car_speed or 0.0))
                else:
                    self.client.load_map_by_name(map if "/" in map else "tracking/" + map,
                                                 car_speed=float(car_speed or 0.0))
            self._find_entities()
            self.client.subscribe(self.camera, ["rgb", "boxes"], "lockstep", with_state=True)
        except BaseException:
            self.close()
            raise

        h, w = self._image_size
        self.observation_space = box(0, 255, (h // self.downscale, w // self.downscale, 3), np.uint8)
        high = np.array([self.max_speed, self.max_speed, self.max_yaw_rate], dtype=np.float32)
        self.action_space = box(-high, high, (3,), np.float32)

        self._frame = None      # the last sim4cv.Frame
        self._rgb = None        # its full-size image (a copy)
        self._info = None
        self._steps = 0
        self._lost = 0
        self._done = True
        self._d_star = None
        self._d_max = None

    # ------------------------------------------------------------------ setup

    def _find_entities(self):
        world = self.client.get_world()
        cameras = {c.name: c for c in world.cameras if c.name}
        if self.camera not in cameras:
            raise ActiveTrackingError("no camera %r (cameras: %s)" % (self.camera, ", ".join(cameras)))
        cam = cameras[self.camera]
        self._image_size = (int(cam.height), int(cam.width))
        by_name = {e.name: e for e in world.entities}
        uav = by_name.get(cam.mounted_on)
        if uav is None or uav.kind != sim4cv.ENTITY_KIND_UAV:
            raise ActiveTrackingError("camera %r is not mounted on a UAV" % self.camera)
        cars = [e for e in world.entities if e.kind == sim4cv.ENTITY_KIND_CAR]
        target = by_name.get("car") if "car" in by_name and by_name["car"].kind == sim4cv.ENTITY_KIND_CAR else \
            (cars[0] if cars else None)
        if target is None:
            raise ActiveTrackingError("the world (%s) has no car to track" % world.scene_name)
        self.uav_id, self.target_id = uav.id, target.id

    @property
    def rng(self):
        """The env's random generator: np_random (gymnasium's, or the same draws without it)."""
        return self.np_random

    # ------------------------------------------------------------------ frames

    def _next_frame(self):
        frame = self.client.step_and_receive(timeout=self.timeout, copy=True)
        self._frame = frame
        self._rgb = np.array(frame.image("rgb"), dtype=np.uint8, copy=True)
        return frame

    def _observation(self):
        k = self.downscale
        if k == 1:
            return self._rgb.copy()
        h, w = self._rgb.shape[0] // k, self._rgb.shape[1] // k
        blocks = self._rgb[:h * k, :w * k].reshape(h, k, w, k, 3).astype(np.float32)
        return np.rint(blocks.mean(axis=(1, 3))).astype(np.uint8)

    def _poses(self, frame):
        entities = {e.id: e for e in frame.entities}
        return entities.get(self.uav_id), entities.get(self.target_id)

    def _measure(self, frame):
        """Ground truth of one frame -> (info dict, per-frame reward)."""
        uav, target = self._poses(frame)
        box = frame.box(self.target_id)
        if box is not None and box.visibility <= 0:
            box = None
        info = {"frame_id": frame.frame_id, "sim_time": frame.sim_time, "box": box,
                "target_distance": self._d_star, "max_distance": self._d_max, "step": self._steps}
        if uav is None or target is None:
            info.update(distance=math.inf, angle=180.0, uav_position=None, target_position=None,
                        heading_deg=None, target_velocity=(0.0, 0.0))
            return info, -1.0
        heading = _heading_deg(uav.orientation)
        dx, dy = target.position[0] - uav.position[0], target.position[1] - uav.position[1]
        distance = math.hypot(dx, dy)
        angle = _wrap_deg(math.degrees(math.atan2(dy, dx)) - heading)
        info.update(distance=distance, angle=angle, uav_position=uav.position, target_position=target.position,
                    heading_deg=heading,
                    target_velocity=_to_heading_frame(target.linear_velocity[0], target.linear_velocity[1], heading))
        reward = 1.0 - abs(distance - self._d_star) / self._d_max - abs(angle) / self.max_angle
        return info, float(min(1.0, max(-1.0, reward)))

    def _command(self, forward, sideways, yaw_rate):
        """A heading-frame velocity -> the world-frame uav_velocity order."""
        uav, _ = self._poses(self._frame)
        heading = _heading_deg(uav.orientation) if uav is not None else 0.0
        vx, vy = _to_world(forward, sideways, heading)
        limit = 20.0  # the daemon's bound per component (docs/protocol.md 16.4)
        self.client.uav_velocity(self.uav_id, max(-limit, min(limit, vx)), max(-limit, min(limit, vy)), 0.0,
                                 max(-180.0, min(180.0, yaw_rate)))

    # ------------------------------------------------------------------ the API

    def reset(self, seed=None, options=None):
        """Back to the world's start, the UAV behind the target; returns
        (observation, info). See the module's docstring."""
        super().reset(seed=seed)
        if self._closed:
            raise ActiveTrackingError("the environment is closed")
        options = dict(options or {})
        rng = self.rng
        client = self.client

        client.reset()
        car_speed = options.get("car_speed")
        if car_speed is None and self.car_speed_range is not None:
            lo, hi = self.car_speed_range
            car_speed = float(rng.uniform(lo, hi))
        if car_speed is not None:
            client.set_speed(self.target_id, float(car_speed))
        jitter = options.get("start_jitter", self.start_jitter) or (0.0, 0.0, 0.0)
        jitter = np.asarray(jitter, dtype=np.float64)
        offset = rng.uniform(-1.0, 1.0, size=3) * jitter  # drawn every reset, so the stream does not depend on it

        client.uav_follow(self.uav_id, self.target_id)
        frame = self._next_frame()
        for _ in range(max(0, self.warmup_frames - 1)):
            frame = self._next_frame()

        # The reward's reference distance, from this frame's geometry.
        uav, target = self._poses(frame)
        if self.target_distance_setting is not None:
            self._d_star = float(self.target_distance_setting)
        else:
            pitch = 60.0
            if frame.message is not None and frame.message.HasField("camera_pose"):
                o = frame.message.camera_pose.orientation
                pitch = _pitch_down_deg((o.w, o.x, o.y, o.z))
            height = (uav.position[2] - target.position[2]) if uav and target else 15.0
            self._d_star = max(0.5, height) / math.tan(math.radians(max(5.0, min(89.0, pitch))))
        self._d_max = float(self.max_distance_setting) if self.max_distance_setting else 3.0 * self._d_star

        if self.start_frames > 0 and np.any(offset != 0.0):
            for _ in range(self.start_frames):
                uav, target = self._poses(self._frame)
                heading = _heading_deg(uav.orientation)
                fwd, left = _to_heading_frame(target.linear_velocity[0], target.linear_velocity[1], heading)
                self._command(fwd + offset[0], left + offset[1], offset[2])
                self._next_frame()
            self._command(0.0, 0.0, 0.0)  # hover until the agent's first action

        self._steps = 0
        info, _ = self._measure(self._frame)
        self._lost = 0 if info["box"] is not None else 1
        info["lost_frames"] = self._lost
        info["car_speed"] = car_speed
        info["start_offset"] = tuple(float(v) for v in offset)
        self._info = info
        self._done = False
        return self._observation(), info

    def step(self, action):
        """Flies `action` = (forward m/s, sideways m/s, yaw rate deg/s) for
        frame_skip frames; returns (observation, reward, terminated,
        truncated, info)."""
        if self._closed:
            raise ActiveTrackingError("the environment is closed")
        if self._done:
            raise ActiveTrackingError("call reset() first: the episode has not begun or is over")
        a = np.asarray(action, dtype=np.float64).reshape(3)
        if not np.all(np.isfinite(a)):
            raise ValueError("action %r is not finite" % (action,))
        forward = float(np.clip(a[0], -self.max_speed, self.max_speed))
        sideways = float(np.clip(a[1], -self.max_speed, self.max_speed))
        yaw_rate = float(np.clip(a[2], -self.max_yaw_rate, self.max_yaw_rate))

        rewards = []
        terminated = False
        info = None
        for _ in range(self.frame_skip):
            self._command(forward, sideways, yaw_rate)
            frame = self._next_frame()
            info, reward = self._measure(frame)
            rewards.append(reward)
            self._lost = 0 if info["box"] is not None else self._lost + 1
            if self._lost >= self.lost_frames or info["distance"] > self._d_max:
                terminated = True
                break
        self._steps += 1
        info["step"] = self._steps
        info["lost_frames"] = self._lost
        truncated = not terminated and self._steps >= self.max_steps
        self._done = terminated or truncated
        self._info = info
        return self._observation(), float(np.mean(rewards)), terminated, truncated, info

    def render(self):
        """The last frame's RGB image at full size, (H, W, 3) uint8 (None before reset)."""
        return None if self._rgb is None else self._rgb.copy()

    # ------------------------------------------------------------------ a scripted baseline

    @staticmethod
    def expert_action(info, k_distance=1.5, k_angle=3.0, feed_forward=True, max_speed=8.0, max_yaw_rate=90.0):
        """A scripted baseline from the ground truth in `info` (not from
        images): forward = k_distance (d - d*) cos(angle) (+ the target's
        forward velocity if feed_forward), sideways = the target's leftward
        velocity (if feed_forward), yaw rate = k_angle * angle; clipped to the
        action bounds. Returns a float32 array for step()."""
        distance, angle = info.get("distance"), info.get("angle")
        if distance is None or not math.isfinite(distance):
            return np.zeros(3, dtype=np.float32)
        d_star = info.get("target_distance") or 0.0
        forward = k_distance * (distance - d_star) * math.cos(math.radians(angle))
        sideways = 0.0
        if feed_forward and info.get("target_velocity") is not None:
            forward += info["target_velocity"][0]
            sideways += info["target_velocity"][1]
        yaw_rate = k_angle * angle
        return np.array([np.clip(forward, -max_speed, max_speed), np.clip(sideways, -max_speed, max_speed),
                         np.clip(yaw_rate, -max_yaw_rate, max_yaw_rate)], dtype=np.float32)
