"""A model of a human pilot flying a camera drone after a target, for
generating tracking sequences whose camera moves as a real UAV's does.

The ground-truth servo keeps the target in the middle of every frame at one
size, so "return the first box forever" scores well. A pilot does not: he
sees the target late (reaction lag), the drone accelerates and turns only so
fast, wind pushes it, and he flies manoeuvres (follow, orbit, fly-by, climb
or descend) and re-frames the shot on purpose, now and then letting the
target slide to the frame's edge or out of it.

He reacts to losing the target: when it has been gone from his screen
(wholly hidden, or out of the frame when he did not look away on purpose)
for a few frames, which he sees only after his reaction time, he gives up
the manoeuvre, flies to put the car straight ahead of where the camera
points, climbs and centres it. That goes through the same lag and limits,
so it shortens long losses; the short ones (a car passing under a crown
for a quarter of a second) stay, as do partial occlusions and edge cuts.

The drone here is simulated client-side (a point mass with limited
acceleration, speed and yaw rate, an Ornstein-Uhlenbeck wind with gusts, a
gimbal with a limited pitch rate); its camera is a world-fixed daemon camera
moved every frame (SetCameraPose), so the daemon renders exactly the pose
the pilot flew. Everything random comes from numpy's generator seeded with
`seed`, and the target's motion from the lockstep daemon, so a sequence
replays byte for byte.

The daemon's cameras cannot change their field of view at run time
(SetCameraPose has no focal length), so there is no zoom; scale changes
come from the pilot's distance and altitude changes.
"""

import collections
import math
from dataclasses import asdict, dataclass

import numpy as np

MODEL = "sim4cv.pilot 2"  # sim4cv.sequences.PILOT_MODEL: a sequence made by another model is made again
MANOEUVRES = ("follow", "orbit", "flyby", "climb", "reframe", "look_away")


@dataclass
class PilotSettings:
    """The pilot's and the drone's limits (SI units, degrees for angles)."""
    max_speed: float = 15.0            # m/s, horizontal
    max_accel: float = 3.5             # m/s^2, horizontal
    max_climb: float = 3.0             # m/s
    max_yaw_rate: float = 40.0         # deg/s
    max_pitch_rate: float = 30.0       # deg/s, the gimbal
    reaction_s: tuple = (0.25, 0.6)    # the pilot's lag, drawn per sequence
    altitude: tuple = (9.0, 32.0)      # m above the target
    distance: tuple = (5.0, 28.0)      # m, horizontal, from the target
    segment_s: tuple = (2.0, 6.0)      # how long one manoeuvre lasts
    wind_sigma: float = 0.8            # m/s, steady turbulence (OU process)
    wind_tau: float = 2.0              # s
    gust_rate: float = 0.06            # gusts per second
    gust_speed: tuple = (2.0, 5.0)     # m/s
    gust_s: tuple = (0.7, 2.0)         # s
    # manoeuvre weights, in MANOEUVRES' order
    weights: tuple = (0.28, 0.2, 0.14, 0.15, 0.2, 0.03)
    steady_start_s: float = 1.5        # the first seconds: plain follow, target centred
    regain_after_s: float = 0.15       # the car wholly hidden this long on his (late) screen: re-centre and climb
    regain_climb: float = 6.0          # m


def _wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _uniform(rng, bounds):
    return float(rng.uniform(bounds[0], bounds[1]))


class Pilot:
    """step(target_position, target_yaw) once per frame, in frame order, with
    the target's true state in the frame just rendered; it returns the
    camera pose (x, y, z, yaw_deg, pitch_down_deg) for the next frame.
    start() gives the first frame's pose."""

    def __init__(self, seed, frame_hz, settings=None, fov_y_deg=60.0, aspect=16 / 9):
        self.settings = settings or PilotSettings()
        self.rng = np.random.default_rng(seed)
        self.seed = int(seed)
        self.dt = 1.0 / float(frame_hz)
        s = self.settings
        self.reaction_s = _uniform(self.rng, s.reaction_s)
        self.lag_frames = max(1, int(round(self.reaction_s / self.dt)))
        self.half_fov_y = math.radians(fov_y_deg) / 2
        self.half_fov_x = math.atan(math.tan(self.half_fov_y) * aspect)
        self.seen = collections.deque(maxlen=self.lag_frames + 2)
        self.wind = np.zeros(3)
        self.gust = np.zeros(3)
        self.gust_left = 0.0
        self.time = 0.0
        self.manoeuvre = None
        self.hidden_s = 0.0            # how long the car has been wholly hidden on the pilot's (late) screen
        self.regaining = False         # pilot.csv's `regain`: he is flying to get the lost car back in view

    # ------------------------------------------------------------------ the plan

    def _new_manoeuvre(self, target, target_yaw):
        s, rng = self.settings, self.rng
        start = self.time < s.steady_start_s
        kind = "follow" if start else MANOEUVRES[int(rng.choice(len(MANOEUVRES), p=np.array(s.weights)
                                                                   / sum(s.weights)))]
        m = {"kind": kind, "left": s.steady_start_s if start else _uniform(rng, s.segment_s),
             "distance": self.manoeuvre["distance"] if self.manoeuvre else 8.66,
             "altitude": self.manoeuvre["altitude"] if self.manoeuvre else 15.0,
             "bearing": math.pi, "rate": 0.0, "point": None,
             "aim_yaw": 0.0, "aim_pitch": 0.0}
        if start:
            return m
        # the framing every manoeuvre carries: a pilot rarely centres exactly
        m["aim_yaw"] = float(rng.normal(0, 0.15)) * self.half_fov_x
        m["aim_pitch"] = float(rng.normal(0, 0.15)) * self.half_fov_y
        if kind in ("follow", "climb", "reframe"):
            m["bearing"] = math.pi + float(rng.uniform(-0.9, 0.9))
        if kind == "climb":
            m["altitude"] = _uniform(rng, s.altitude)
            m["distance"] = _uniform(rng, s.distance)
        elif kind == "orbit":
            m["altitude"] = _uniform(rng, s.altitude)
            m["rate"] = float(rng.choice([-1, 1])) * math.radians(_uniform(rng, (10, 25)))
            m["distance"] = _uniform(rng, (s.distance[0] + 3, s.distance[1]))
            m["bearing"] = None  # starts from where the drone is
        elif kind == "flyby":
            # hold a point beside the target's path ahead; it passes under the camera
            m["altitude"] = _uniform(rng, s.altitude)
            ahead = _uniform(rng, (8, 25))
            side = float(rng.choice([-1, 1])) * _uniform(rng, (4, 14))
            # the camera must swing round as fast as the car passes: he knows how fast his drone yaws
            speed = float(np.hypot(*self._perceived()[2][:2]))
            side = math.copysign(max(abs(side), min(20.0, 1.3 * speed / math.radians(s.max_yaw_rate))), side)
            c, sn = math.cos(target_yaw), math.sin(target_yaw)
            m["point"] = (target[0] + ahead * c - side * sn, target[1] + ahead * sn + side * c)
        elif kind == "reframe":
            # composition: the target deliberately towards a side or a corner, sometimes cut by the edge
            m["aim_yaw"] = float(rng.choice([-1, 1])) * _uniform(rng, (0.45, 0.95)) * self.half_fov_x
            m["aim_pitch"] = float(rng.choice([-1, 1])) * _uniform(rng, (0.2, 0.85)) * self.half_fov_y
        elif kind == "look_away":
            # the pilot looks at something else for a moment: the target leaves the frame
            m["left"] = _uniform(rng, (0.4, 1.2))
            m["aim_yaw"] = float(rng.choice([-1, 1])) * _uniform(rng, (1.25, 1.6)) * self.half_fov_x
        return m

    # ------------------------------------------------------------------ flying

    def start(self, target, target_yaw):
        """The first frame's pose: behind the target at the start distance, looking at it."""
        target = np.asarray(target, dtype=float)
        self.manoeuvre = self._new_manoeuvre(target, target_yaw)
        m = self.manoeuvre
        self.pos = np.array([target[0] + m["distance"] * math.cos(target_yaw + m["bearing"]),
                             target[1] + m["distance"] * math.sin(target_yaw + m["bearing"]),
                             target[2] + m["altitude"]])
        self.vel = np.zeros(3)
        self.yaw = math.atan2(target[1] - self.pos[1], target[0] - self.pos[0])
        self.pitch = math.atan2(m["altitude"], m["distance"])
        self.seen.append((target, float(target_yaw), 1.0))
        return self.pose()

    def pose(self):
        return (float(self.pos[0]), float(self.pos[1]), float(self.pos[2]), math.degrees(self.yaw),
                math.degrees(self.pitch))

    def _perceived(self):
        """What the pilot acts on: the target as it was reaction_s ago, and its velocity then."""
        old, yaw, visibility = self.seen[0]
        older = self.seen[1][0] if len(self.seen) > 1 else old
        return old, yaw, (older - old) / self.dt if len(self.seen) > 1 else np.zeros(3), visibility

    def _wind_step(self):
        s, rng, dt = self.settings, self.rng, self.dt
        self.wind += -self.wind / s.wind_tau * dt + s.wind_sigma * math.sqrt(2 * dt / s.wind_tau) * rng.normal(0, 1, 3)
        self.wind[2] *= 0.3
        if self.gust_left > 0:
            self.gust_left -= dt
            if self.gust_left <= 0:
                self.gust[:] = 0
        elif rng.random() < s.gust_rate * dt:
            angle = rng.uniform(0, 2 * math.pi)
            self.gust = _uniform(rng, s.gust_speed) * np.array([math.cos(angle), math.sin(angle), 0.0])
            self.gust_left = _uniform(rng, s.gust_s)
        return self.wind + self.gust

    def step(self, target, target_yaw, visibility=None):
        """visibility: the fraction of the target not hidden in the frame just rendered (0: wholly hidden
        or out of the frame; None: unknown, taken as visible); the pilot sees it late, as the target."""
        s, dt = self.settings, self.dt
        target = np.asarray(target, dtype=float)
        self.seen.append((target, float(target_yaw), 1.0 if visibility is None else float(visibility)))
        while len(self.seen) > self.lag_frames + 1:
            self.seen.popleft()
        self.time += dt
        m = self.manoeuvre
        m["left"] -= dt
        if m["left"] <= 0:
            self.manoeuvre = m = self._new_manoeuvre(target, target_yaw)
        seen, seen_yaw, seen_vel, seen_visibility = self._perceived()
        # the car gone from his screen (not because he looked away on purpose): re-centre it and climb
        looking_away = m["kind"] == "look_away"
        self.hidden_s = self.hidden_s + dt if seen_visibility <= 0 and not looking_away else 0.0
        regain = self.hidden_s > s.regain_after_s
        if regain and not self.regaining:
            # he gives up the manoeuvre: the car straight ahead of where the camera points, higher, centred
            m.update(point=None, rate=0.0, bearing=_wrap(self.yaw + math.pi - seen_yaw), aim_yaw=0.0, aim_pitch=0.0,
                     altitude=min(m["altitude"] + s.regain_climb, s.altitude[1]),
                     distance=min(m["distance"], s.distance[1] * 0.6), left=max(m["left"], 1.5))

        # where the pilot wants the drone
        if m["point"] is not None:
            want = np.array([m["point"][0], m["point"][1], seen[2] + m["altitude"]])
            feed = np.zeros(3)
        else:
            if m["bearing"] is None:
                m["bearing"] = math.atan2(self.pos[1] - seen[1], self.pos[0] - seen[0]) - seen_yaw
            m["bearing"] += m["rate"] * dt
            around = seen_yaw + m["bearing"]
            want = np.array([seen[0] + m["distance"] * math.cos(around), seen[1] + m["distance"] * math.sin(around),
                             seen[2] + m["altitude"]])
            feed = seen_vel
        accel = 0.8 * (want - self.pos) + 1.6 * (feed - self.vel)
        horizontal = math.hypot(accel[0], accel[1])
        if horizontal > s.max_accel:
            accel[:2] *= s.max_accel / horizontal
        accel[2] = float(np.clip(accel[2], -s.max_accel, s.max_accel))
        self.regaining = regain
        self.vel += accel * dt
        speed = math.hypot(self.vel[0], self.vel[1])
        if speed > s.max_speed:
            self.vel[:2] *= s.max_speed / speed
        self.vel[2] = float(np.clip(self.vel[2], -s.max_climb, s.max_climb))
        self.pos += (self.vel + self._wind_step()) * dt
        self.pos[2] = max(self.pos[2], seen[2] + s.altitude[0] * 0.6)

        # where the pilot points the camera: at the target as he saw it, with his framing
        dx, dy = seen[0] - self.pos[0], seen[1] - self.pos[1]
        want_yaw = math.atan2(dy, dx) + m["aim_yaw"]
        want_pitch = math.atan2(self.pos[2] - seen[2], math.hypot(dx, dy)) - m["aim_pitch"]
        max_yaw, max_pitch = math.radians(s.max_yaw_rate) * dt, math.radians(s.max_pitch_rate) * dt
        self.yaw = _wrap(self.yaw + float(np.clip(2.5 * dt * _wrap(want_yaw - self.yaw), -max_yaw, max_yaw)))
        self.pitch += float(np.clip(3.0 * dt * (want_pitch - self.pitch), -max_pitch, max_pitch))
        self.pitch = float(np.clip(self.pitch, math.radians(5), math.radians(89)))
        return self.pose()

    def record(self):
        """This frame's row of pilot.csv (PILOT_HEADER)."""
        m = self.manoeuvre
        wind = self.wind + self.gust
        return [m["kind"], round(math.degrees(m["aim_yaw"]), 3), round(math.degrees(m["aim_pitch"]), 3),
                round(float(wind[0]), 4), round(float(wind[1]), 4), round(float(self.gust_left > 0), 0),
                int(self.regaining)]

    def description(self):
        """What sequence.json records so a reader knows how the camera flew."""
        return {"model": MODEL, "seed": self.seed, "reaction_s": round(self.reaction_s, 4),
                "settings": asdict(self.settings)}


PILOT_HEADER = ["manoeuvre", "aim_yaw_deg", "aim_pitch_deg", "wind_x", "wind_y", "gust", "regain"]


def take_the_camera(client, world, target_id, seed, frame_hz, camera="uav", name="pilot", settings=None):
    """Replaces the map's UAV by a piloted world-fixed camera like its camera
    `camera` (same size and field of view): removes the UAV (so it does not
    fly through the shots), adds the camera `name` at the pilot's first pose.
    Returns the Pilot; move the camera with set_camera_pose(name, *pilot.step(...))."""
    info = next(c for c in world.cameras if c.name == camera)
    uav = next((e for e in world.entities if e.name == info.mounted_on), None)
    if uav is not None:
        client.remove(uav.id)
    state = client.get_state()
    car = next(e for e in state.entities if e.id == target_id)
    q = car.orientation
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y ** 2 + q.z ** 2))
    pilot = Pilot(seed, frame_hz, settings, fov_y_deg=info.fov_y_deg, aspect=info.width / info.height)
    x, y, z, yaw_deg, pitch_deg = pilot.start((car.position.x, car.position.y, car.position.z), yaw)
    client.add_camera(name, "", info.width, info.height, info.fov_y_deg, pitch_down_deg=pitch_deg, yaw_deg=yaw_deg,
                      offset=(x, y, z))
    return pilot
