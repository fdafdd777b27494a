"""A driving environment for reinforcement learning, Gymnasium style
(docs/driving.md, "Driving environment (Gym)").

    from sim4cv.driving_env import DrivingEnv
    with DrivingEnv(maps="train", randomize=True) as env:      # a lockstep sim4cvd of its own per map
        obs, info = env.reset(seed=0)
        for _ in range(1000):
            action = env.reference_action()    # or env.action_space.sample(), or your policy(obs["rgb"])
            obs, reward, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                obs, info = env.reset()

`DrivingEnv` subclasses `gymnasium.Env` when `import gymnasium` works and
is otherwise a plain class with the same methods (the same code runs in
both cases); its spaces are `gymnasium.spaces.Box` / `Dict` or, without
gymnasium, the stand-ins `Box` and `DictSpace` (sim4cv.env_base)
below (shape, dtype, low, high, sample(), contains()).

Episode (reset(seed=None, options=None)): from the env's seeded generator
(gymnasium's np_random, or numpy's default_rng(seed): the same draws) it
picks a map of `maps` (uniformly), one of its routes (uniformly) and a
start point u (arc length, uniform over the route; an open route keeps
WAYPOINT_COUNT * WAYPOINT_STEP_M before its end); options["map"] (index or
file), options["route"], options["u"] and options["conditions"] (a preset)
override the draws. The map's own car and UAV are removed and the ego car
is spawned at rest on the right-lane centre at u, heading along the lane,
with a camera mounted on it (`camera`, default the dataset's first-person
camera, sim4cv.driving_dataset.CAMERA_SETTINGS). The daemon (lockstep,
no traffic) is started for a new map and reused, through a Reset, when the
map is unchanged: the world is then exactly as a fresh daemon's, so the
same seed gives the same first image.

Action: (steering, throttle, brake), float32, steering in [-1, 1]
(positive: right, as sim4cv Controls), throttle and brake in [0, 1].
Values outside are clipped (+-inf too); a NaN raises ValueError naming the
component. Above `speed_limit` (m/s; None: none) the throttle is cut to 0.
One step = one lockstep frame (1 / frame_hz simulated seconds).

Observation: a dict, channel name -> numpy array (a copy) of the camera's
frame, for each of `channels`: rgb (H, W, 3) uint8, depth (H, W) float32
metres, mask (H, W) uint16 instance ids, semantic (H, W) uint8 class ids,
normals (H, W, 3) float32, flow (H, W, 2) float32 pixels. "boxes" carries
no pixels: the frame's ground-truth boxes are put in info["boxes"] instead.

Reward, per step, with u the car's arc length along its route (unwrapped,
sim4cv.driving_metrics.Progress), d its signed distance from the right-lane
centre (m, positive to the right) after the step, and dt = 1 / frame_hz:

    r = (u_t - u_{t-1})  -  deviation_weight * |d_t| * dt  -  terminal_penalty * [terminated by a failure]

progress in metres (negative when driving backwards) minus the deviation
integrated over the step (default weight 2 per second: a second spent 1 m
off the centre costs 2 m of progress) minus `terminal_penalty` (10) on the
step that ends the episode with a lane departure or a collision.

terminated: a lane departure (|d| > `departure_m`, by default
driving_metrics.LANE_DEPARTURE_M = 1 m: the 2 m wide car's side leaves the
4 m lane), a collision with one of the map's objects
(driving_metrics.Collisions), or, on an open route, its end reached (no
penalty). truncated: `max_seconds` of simulated time since reset.

info: deviation_m, u, progress_m (u - u at reset), speed (m/s), collisions
(count this episode), lane_departure (bool), sim_time (s since reset),
step, x, y, yaw_deg, reason (None, "lane_departure", "collision",
"route_end", "time_limit"), map, map_path, route, u0, conditions (preset,
hour, ... in force), steering/throttle/brake (applied), boxes (if asked).

Domain randomisation (randomize=True or "preset"): every reset draws a
preset of `randomize_presets` and an hour within +-HOUR_JITTER_H of its
own and sends SetConditions; randomize="daemon" hands the daemon a seed
(SetConditions.randomize_seed: preset, hour, exposure and a colour jitter
per object, docs/protocol.md). Both come from a seed drawn from the env's
generator every reset (whether randomizing or not), so the same reset seed
gives the same conditions, and the map/route/u draws do not depend on it.
The daemon's draws use a period of DAEMON_DRAW_PERIOD frames, so they
depend on the seed only, not on how many episodes the daemon has run.
Conditions change the RGB only, and only at quality "full" ("fast" is
flat-shaded).
"""

import math
import os
from typing import Optional, Sequence

import numpy as np

import sim4cv
from . import driving_control as dc
from . import driving_metrics as dm
from .channel_table import PIXEL_CHANNELS
from .daemon import OwnDaemon
from .driving_dataset import CAMERA_SETTINGS, WAYPOINT_COUNT, WAYPOINT_STEP_M, RoutePath, parse_map, \
    resolve_maps
from .driving_eval import ReferencePolicy, yaw_of
from .env_base import DictSpace, SimEnv, box, dict_space  # noqa: F401 (DictSpace: re-exported)
from .errors import ServerError


EGO, EGO_CAMERA = "ego", "ego_cam"
DEFAULT_SPEED_LIMIT = 8.0      # m/s, as the closed-loop evaluation's speed cap (driving_eval.DEFAULT_SPEED)
DEFAULT_DEVIATION_WEIGHT = 2.0  # per second per metre of |deviation|
DEFAULT_TERMINAL_PENALTY = 10.0
HOUR_JITTER_H = 1.0
DAEMON_DRAW_PERIOD = 10 ** 9  # frames (SetConditions' maximum): one draw per episode, see _set_conditions
# docs/protocol.md, SetConditions: each preset's own hour
PRESET_HOURS = {"clear_noon": 12.5, "clear_morning": 7.5, "overcast": 12.0, "fog": 10.0, "dusk": 17.8,
                "night": 23.0, "rain": 15.0}
PRESETS = tuple(PRESET_HOURS)
CAMERA_KEYS = ("name", "width", "height", "fov_y_deg", "pitch_down_deg", "yaw_deg", "forward_m", "left_m",
               "above_body_m", "gimbal")
ACTION_NAMES = ("steering", "throttle", "brake")
# channel -> (components, dtype, low, high) of its observation array: the
# element's whole range, but where the channel's values have narrower bounds.
_ELEMENT_SPECS = {"u8": (np.uint8, 0, 255), "u16": (np.uint16, 0, 65535), "f32": (np.float32, -np.inf, np.inf)}
_NARROWER = {"depth": (0.0, np.inf), "normals": (-1.0, 1.0)}
CHANNEL_SPECS = {name: (components, _ELEMENT_SPECS[element][0]) + _NARROWER.get(name, _ELEMENT_SPECS[element][1:])
                 for name, _, _, element, components, _, _ in PIXEL_CHANNELS}
NON_PIXEL_CHANNELS = ("boxes",)


class DrivingEnvError(RuntimeError):
    """The environment cannot run (no maps, a daemon that fails, a closed env); the message says why."""




# ----------------------------------------------------------------------------- the environment

class DrivingEnv(SimEnv):
    """Drive the ego car along a route of a driving map from its camera's
    images. See the module's docstring (and docs/driving.md, "Driving
    environment (Gym)") for the spaces, reward and episode rules.

    Arguments: maps ("train", "val", "test", a .map file, or a list of
    them); surroundings (of the named sets); camera (a dict overriding
    CAMERA_SETTINGS' width, height, fov_y_deg, pitch_down_deg and the mount:
    forward_m, left_m, above_body_m over the body's centre, yaw_deg);
    channels; frame_hz; max_seconds; speed_limit (m/s, None: none);
    conditions (a preset for every episode; None: the daemon's clear_noon);
    quality ("full" or "fast"; None: the daemon's full); randomize (False,
    True or "preset", "daemon"); randomize_presets; deviation_weight,
    terminal_penalty, departure_m (the reward and termination);
    daemon_args (more sim4cvd flags); timeout (s, per request).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, maps="train", surroundings=("desert", "urban"), camera: Optional[dict] = None,
                 channels: Sequence[str] = ("rgb",), frame_hz: float = 30.0, max_seconds: float = 60.0,
                 speed_limit: Optional[float] = DEFAULT_SPEED_LIMIT, conditions: Optional[str] = None,
                 quality: Optional[str] = None, randomize=False, randomize_presets: Sequence[str] = PRESETS,
                 deviation_weight: float = DEFAULT_DEVIATION_WEIGHT,
                 terminal_penalty: float = DEFAULT_TERMINAL_PENALTY, departure_m: float = dm.LANE_DEPARTURE_M,
                 daemon_args: Sequence[str] = (), render_mode: Optional[str] = "rgb_array",
                 timeout: float = 30.0, name: str = "sim4cv.driving_env"):
        self.render_mode = render_mode
        self.name = name
        self.timeout = float(timeout)
        self.daemon = None
        self.client = None
        self._closed = False
        self._map_path = None

        specs = [maps] if isinstance(maps, str) else list(maps)
        if not specs:
            raise ValueError("DrivingEnv: maps is empty")
        self.surroundings = [surroundings] if isinstance(surroundings, str) else list(surroundings)
        try:
            self.maps = [p for p, _ in resolve_maps(specs, self.surroundings)]
        except RuntimeError as e:
            raise DrivingEnvError(str(e)) from None
        self._map_info = {}

        unknown = sorted(set(camera or {}) - set(CAMERA_KEYS))
        if unknown:
            raise ValueError("DrivingEnv: unknown camera setting(s) %s; known: %s"
                             % (", ".join(unknown), ", ".join(CAMERA_KEYS)))
        self.camera = dict(CAMERA_SETTINGS, **(camera or {}))
        self.channels = [str(c).lower() for c in channels]
        for c in self.channels:
            if c not in CHANNEL_SPECS and c not in NON_PIXEL_CHANNELS:
                raise ValueError("DrivingEnv: unknown channel %r; expected some of %s"
                                 % (c, ", ".join(list(CHANNEL_SPECS) + list(NON_PIXEL_CHANNELS))))
        if not any(c in CHANNEL_SPECS for c in self.channels):
            raise ValueError("DrivingEnv: channels %s hold no pixel channel (%s)"
                             % (self.channels, ", ".join(CHANNEL_SPECS)))

        self.frame_hz = float(frame_hz)
        self.max_seconds = float(max_seconds)
        if not (self.frame_hz > 0 and self.max_seconds > 0):
            raise ValueError("DrivingEnv: frame_hz and max_seconds must be positive")
        self.speed_limit = None if speed_limit is None else float(speed_limit)
        for p in ([conditions] if conditions else []) + list(randomize_presets):
            if p not in PRESET_HOURS:
                raise ValueError("DrivingEnv: unknown conditions preset %r; expected one of %s"
                                 % (p, ", ".join(PRESETS)))
        if not randomize_presets:
            raise ValueError("DrivingEnv: randomize_presets is empty")
        self.conditions = conditions
        self.quality = quality
        if randomize is True:
            randomize = "preset"
        if randomize not in (False, None, "preset", "daemon"):
            raise ValueError("DrivingEnv: randomize must be False, True, 'preset' or 'daemon', got %r" % (randomize,))
        self.randomize = randomize or False
        self.randomize_presets = tuple(randomize_presets)
        self.deviation_weight = float(deviation_weight)
        self.terminal_penalty = float(terminal_penalty)
        self.departure_m = float(departure_m)
        self.daemon_args = list(daemon_args)

        w, h = int(self.camera["width"]), int(self.camera["height"])
        observation = {}
        for c in self.channels:
            if c in CHANNEL_SPECS:
                components, dtype, low, high = CHANNEL_SPECS[c]
                shape = (h, w) if components == 1 else (h, w, components)
                observation[c] = box(low, high, shape, dtype)
        self.observation_space = dict_space(observation)
        self.action_space = box(np.array([-1.0, 0.0, 0.0], dtype=np.float32),
                                 np.array([1.0, 1.0, 1.0], dtype=np.float32), (3,), np.float32)

        self.path = None        # the episode's RoutePath
        self.progress = None    # its driving_metrics.Progress
        self._collisions = None
        self._frame = None
        self._obs = None
        self._info = None
        self._pose = None       # (x, y, yaw rad)
        self._speed = 0.0
        self._done = True
        self._t0 = 0.0
        self._steps = 0
        self._ego = None
        self._reference = ReferencePolicy()
        self._override = False  # the last episode's conditions came from reset's options
        self._episode = None
        self._u0 = 0.0
        self._lap = None
        self.metadata = dict(self.metadata, render_fps=self.frame_hz)

    # ------------------------------------------------------------------ the daemon

    def _option_map(self, m) -> str:
        """options["map"]: an index into self.maps or a .map file."""
        if isinstance(m, (int, np.integer)):
            if not 0 <= int(m) < len(self.maps):
                raise ValueError("DrivingEnv.reset: options['map'] %d is not an index of the %d maps"
                                 % (m, len(self.maps)))
            return self.maps[int(m)]
        if isinstance(m, str) and os.path.isfile(m):
            return os.path.abspath(m)
        raise ValueError("DrivingEnv.reset: options['map'] must be an index of env.maps or a .map file, got %r"
                         % (m,))

    def _map(self, path: str) -> dict:
        if path not in self._map_info:
            self._map_info[path] = parse_map(path)
        return self._map_info[path]

    def _start_world(self, map_path: str, fresh: bool = False):
        """A lockstep daemon on `map_path` with a fresh world: a new one for
        a new map (or when `fresh`), else the running one after a Reset (and
        a new session: the old subscription's camera is gone with the reset)."""
        if self.client is not None:
            try:
                self.client.close()
            except Exception:  # noqa: BLE001 - it is being replaced
                pass
            self.client = None
        if self.daemon is not None and (fresh or self._map_path != map_path or not self.daemon.running()):
            self.daemon.stop()
            self.daemon = None
        if self.daemon is None:
            self._map_path = None
            flags = ["--map", map_path, "--traffic-cars", "0", "--traffic-parked", "0",
                     "--traffic-pedestrians", "0", "--frame-hz", repr(self.frame_hz)]
            if self.conditions:
                flags += ["--conditions", self.conditions]
            if self.quality:
                flags += ["--quality", self.quality]
            try:
                self.daemon = OwnDaemon(flags + self.daemon_args, mode="lockstep")
            except RuntimeError as e:
                raise DrivingEnvError("cannot start sim4cvd for %s: %s" % (map_path, e)) from None
            self._map_path = map_path
            self.client = sim4cv.connect(self.daemon.address, name=self.name, timeout=self.timeout)
        else:
            with sim4cv.connect(self.daemon.address, name=self.name, timeout=self.timeout) as c:
                c.reset()
            self.client = sim4cv.connect(self.daemon.address, name=self.name, timeout=self.timeout)

    def _spawn(self, x: float, y: float, yaw: float):
        client = self.client
        for entity in client.get_world().entities:
            if entity.name in ("car", "uav"):  # the map's own car and the UAV filming it
                client.remove(entity.id)
        self._ego = client.spawn("car", EGO, x, y, 0.0, math.degrees(yaw))
        cam = self.camera
        gimbal = bool(cam.get("gimbal", False))
        offset = (float(cam.get("forward_m", 0.0)), float(cam.get("left_m", 0.0)), float(cam.get("above_body_m", 0.0)))
        client.add_camera(EGO_CAMERA, mounted_on=EGO, width=int(cam["width"]), height=int(cam["height"]),
                          fov_y_deg=float(cam["fov_y_deg"]), pitch_down_deg=float(cam["pitch_down_deg"]),
                          yaw_deg=float(cam.get("yaw_deg", 0.0)), gimbal=gimbal, offset=offset)
        client.subscribe(EGO_CAMERA, self.channels, "lockstep", with_state=True)

    def _set_conditions(self, preset: Optional[str], cond_seed: int, rng_draw: bool) -> dict:
        """SetConditions for this episode; returns what is in force."""
        if rng_draw and self.randomize == "daemon":
            # per-episode draws (period 0) would take the daemon's episode count as the draw index;
            # a period longer than any episode makes it draw 0 of this seed, the same on a new daemon
            world = self.client.set_conditions(randomize_seed=cond_seed, randomize_every_frames=DAEMON_DRAW_PERIOD)
        elif preset is not None or (rng_draw and self.randomize == "preset"):
            if preset is None:
                r = np.random.default_rng(cond_seed)
                preset = self.randomize_presets[int(r.integers(len(self.randomize_presets)))]
                hour = float(np.clip(PRESET_HOURS[preset] + r.uniform(-HOUR_JITTER_H, HOUR_JITTER_H), 0.0, 24.0))
            else:
                hour = PRESET_HOURS[preset]
            world = self.client.set_conditions(preset=preset, hour=hour)
        else:
            world = self.client.get_world()
        c = world.conditions
        out = {"preset": c.preset, "hour": round(float(c.hour), 6), "quality": c.quality,
               "exposure": round(float(c.exposure), 6)}
        if c.randomize_seed:
            out["randomize_seed"] = int(c.randomize_seed)
        return out

    # ------------------------------------------------------------------ frames

    def _receive(self):
        frame = self.client.step_and_receive(timeout=self.timeout, copy=True)
        self._frame = frame
        self._obs = {c: np.array(frame.image(c), copy=True) for c in self.channels if c in CHANNEL_SPECS}
        ego = next((e for e in frame.entities if e.id == self._ego), None)
        if ego is None:
            raise DrivingEnvError("frame %d carries no state of the ego car" % frame.frame_id)
        self._pose = (ego.position[0], ego.position[1], yaw_of(ego.orientation))
        self._speed = math.hypot(ego.linear_velocity[0], ego.linear_velocity[1])
        return frame

    def _observation(self):
        return {k: v.copy() for k, v in self._obs.items()}

    def _base_info(self, deviation: float) -> dict:
        x, y, yaw = self._pose
        info = {"deviation_m": deviation, "u": self.progress.u, "progress_m": self.progress.u - self._u0,
                "speed": self._speed, "collisions": self._collisions.count,
                "lane_departure": abs(deviation) > self.departure_m,
                "sim_time": self._frame.sim_time - self._t0, "step": self._steps, "x": x, "y": y,
                "yaw_deg": math.degrees(yaw), "map": self._episode["map"], "map_path": self._episode["map_path"],
                "route": self._episode["route"], "u0": self._u0, "conditions": self._episode["conditions"],
                "reason": None}
        if "boxes" in self.channels:
            info["boxes"] = list(self._frame.boxes)
        return info

    # ------------------------------------------------------------------ the API

    def reset(self, *, seed=None, options=None):
        """A new episode: a map, route and start point (seeded draws or
        options map/route/u/conditions), the car at rest on the lane centre;
        returns (observation, info)."""
        super().reset(seed=seed)
        if self._closed:
            raise DrivingEnvError("the environment is closed")
        options = dict(options or {})
        unknown = sorted(set(options) - {"map", "route", "u", "conditions"})
        if unknown:
            raise ValueError("DrivingEnv.reset: unknown option(s) %s; known: map, route, u, conditions"
                             % ", ".join(unknown))
        rng = self.np_random
        # the draws happen every reset, in this order, whatever the options say
        map_index = int(rng.integers(len(self.maps)))
        route_draw = float(rng.random())
        u_draw = float(rng.random())
        cond_seed = int(rng.integers(1, 2 ** 63))

        if "map" in options:
            map_path = self._option_map(options["map"])
        else:
            map_path = self.maps[map_index]
        info = self._map(map_path)
        routes = sorted(info["routes"])
        if not routes:
            raise DrivingEnvError("%s has no routes" % map_path)
        route = options.get("route", routes[min(int(route_draw * len(routes)), len(routes) - 1)])
        if route not in info["routes"]:
            raise ValueError("DrivingEnv.reset: map %s has no route %r (routes: %s)"
                             % (info["name"], route, ", ".join(routes)))
        path = RoutePath(info, route)
        span = path.length if path.closed else max(path.length - WAYPOINT_COUNT * WAYPOINT_STEP_M - 10.0, 0.0)
        u0 = float(options["u"]) if "u" in options else u_draw * span
        if not math.isfinite(u0):
            raise ValueError("DrivingEnv.reset: options['u'] must be finite, got %r" % (options["u"],))
        preset = options.get("conditions")
        if preset is not None and preset not in PRESET_HOURS:
            raise ValueError("DrivingEnv.reset: unknown conditions preset %r; expected one of %s"
                             % (preset, ", ".join(PRESETS)))
        if preset is None and not self.randomize and self._override:
            # a Reset keeps the conditions an earlier episode's options set: back to the env's own
            preset = self.conditions or "clear_noon"
        self._override = "conditions" in options

        try:
            # a preset after the daemon's randomisation: a new daemon, as the randomised exposure and
            # colour jitter would stay in force
            self._start_world(map_path, fresh=self.randomize == "daemon" and preset is not None)
            conditions = self._set_conditions(preset, cond_seed, preset is None)
            x, y, yaw = path.point(u0)
            self._spawn(x, y, yaw)
            self._receive()
        except (ServerError, ConnectionError, TimeoutError) as e:
            raise DrivingEnvError("sim4cvd on %s: %s" % (map_path, e)) from e

        self.path = path
        self._lap = None if path.closed else path.length - WAYPOINT_COUNT * WAYPOINT_STEP_M
        self.progress = dm.Progress(path, u0)
        self._collisions = dm.Collisions(info["objects"])
        x, y, yaw = self._pose
        deviation = self.progress.update(x, y)
        self._collisions.update(x, y, yaw)
        self._u0 = u0
        self._t0 = self._frame.sim_time
        self._steps = 0
        self._episode = {"map": info["name"], "map_path": map_path, "route": route, "conditions": conditions}
        self._info = self._base_info(deviation)
        self._info.update(steering=0.0, throttle=0.0, brake=0.0)
        self._done = False
        return self._observation(), dict(self._info)

    def step(self, action):
        """Applies `action` = (steering, throttle, brake) for one frame;
        returns (observation, reward, terminated, truncated, info)."""
        if self._closed:
            raise DrivingEnvError("the environment is closed")
        if self._done:
            raise DrivingEnvError("call reset() first: the episode has not begun or is over")
        a = np.asarray(action, dtype=np.float64)
        if a.size != 3:
            raise ValueError("DrivingEnv.step: action must be 3 numbers (steering, throttle, brake), got %r"
                             % (action,))
        a = a.reshape(3)
        for name, value in zip(ACTION_NAMES, a):
            if math.isnan(value):
                raise ValueError("DrivingEnv.step: %s is NaN in action %s; actions must be numbers "
                                 "(out-of-range values and infinities are clipped)" % (name, list(a)))
        steering = float(np.clip(a[0], -1.0, 1.0))
        throttle = float(np.clip(a[1], 0.0, 1.0))
        brake = float(np.clip(a[2], 0.0, 1.0))
        if self.speed_limit is not None and self._speed >= self.speed_limit:
            throttle = 0.0

        try:
            self.client.send_controls(self._ego, steering, throttle, brake)
            self._receive()
        except (ServerError, ConnectionError, TimeoutError) as e:
            raise DrivingEnvError("sim4cvd on %s: %s" % (self._map_path, e)) from e
        self._steps += 1
        x, y, yaw = self._pose
        u_before = self.progress.u
        deviation = self.progress.update(x, y)
        hit = self._collisions.update(x, y, yaw)
        info = self._base_info(deviation)
        info.update(steering=steering, throttle=throttle, brake=brake)

        dt = 1.0 / self.frame_hz
        reward = (self.progress.u - u_before) - self.deviation_weight * abs(deviation) * dt
        terminated = False
        if hit:
            terminated, info["reason"] = True, "collision"
        elif info["lane_departure"]:
            terminated, info["reason"] = True, "lane_departure"
        if terminated:
            reward -= self.terminal_penalty
        elif self._lap is not None and self.progress.u >= self._lap:
            terminated, info["reason"] = True, "route_end"
        truncated = not terminated and info["sim_time"] >= self.max_seconds - 1e-6
        if truncated:
            info["reason"] = "time_limit"
        self._done = terminated or truncated
        self._info = info
        return self._observation(), float(reward), terminated, truncated, dict(info)

    def reference_action(self, speed: Optional[float] = None) -> np.ndarray:
        """A baseline from the ground truth (not from the images): the
        route's true waypoints (driving_eval.ReferencePolicy) through the
        case study's controller (driving_control.controls_from_waypoints)
        with a speed cap (default: speed_limit, else 8 m/s). float32 array."""
        if self.progress is None:
            raise DrivingEnvError("call reset() first")
        cap = speed if speed is not None else (self.speed_limit or DEFAULT_SPEED_LIMIT)
        w = self._reference.waypoints(None, self._pose, self.progress)
        return np.array(dc.controls_from_waypoints(w, speed=self._speed, max_speed=cap), dtype=np.float32)

    def render(self):
        """The last frame's RGB image, (H, W, 3) uint8 (None before reset or without the rgb channel)."""
        if self._obs is None or "rgb" not in self._obs:
            return None
        return self._obs["rgb"].copy()
