"""The driving case study's controller (docs/driving.md, "Network and
controller"): sim4cv Controls (steering, throttle, brake) from the 4
predicted waypoints v1 h1 ... v4 h4 (metres; v forward, h POSITIVE TO THE
RIGHT, as labels.csv and sim4cv.driving_labels).

Steering (the paper's rule): the wheel angle is the angle to the first
waypoint, atan(h1 / v1), scaled to Controls.steering by the car's maximum
front wheel angle (CarParams.max_steering_deg, 35 deg by default,
docs/vehicles.md "Parameters"):

    steering = clip(gain * atan2(h1, v1) / radians(max_steering_deg), -1, 1)

positive = right, like Controls.steering (+1 = full right, the wheels at
max_steering_deg). v1 <= 0 (the point beside or behind the car): full lock
towards the side of h1 (0 if h1 == 0).

Throttle from the last waypoint's sideways offset |h4| (8 m ahead): high on
straights, lower as a turn approaches:

    throttle = clip(t_max - k * |h4|, t_min, t_max)

and 0 when `speed` >= `max_speed` (the optional speed cap). Brake is 0.

Slowing for turns (beyond the paper, off by default): throttle alone
barely slows the car (0.3 holds 8 m/s), and at 8 m/s a tight right turn
(the inner lane) is at the edge of the tyres' grip: a car there runs wide
even at full lock. With `slowdown` > 0 the cap falls with |h4|, and the
car brakes when it is faster than the cap:

    cap = max(min(MIN_TURN_SPEED, max_speed), max_speed - slowdown * |h4|)
    brake = clip(BRAKE_PER_M_S * (speed - cap), 0, 1) when speed > cap

Bend correction (beyond the paper, off by default): aimed at a point l
ahead on a bend of curvature kappa, the car cuts the bend's inside (with the
shipped network, 401 of the 635 validation frames beyond 25 cm were on the
inside of left bends). With `bend` C > 0 the aim point moves towards the
outside by C times the chord's offset from the arc, kappa * l^2 / 2, with
kappa the signed curvature of the circle through waypoints 1-3 (positive
bending right) and l the aim point's distance:

    h_aim -= C * kappa * (v_aim^2 + h_aim^2) / 2      while |h4| <= bend_limit

Beyond `bend_limit` metres of |h4| (a swerve past a parked car, a junction's
sharp turn) the aim point stays where it is: there the correction delayed
the swerve and the car missed a pass.

`Controller` holds the choices beyond the paper's rule (the waypoint
steered at, the gain, slowing for turns, the bend correction) once, for every command that
drives (evaluate, dagger, compare: `add_arguments`, `from_arguments`).

Pure functions, no daemon, no numpy.
"""

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

MAX_STEERING_DEG = 35.0  # CarParams.max_steering_deg (docs/vehicles.md)
THROTTLE_MAX = 1.0       # on a straight (|h4| = 0)
THROTTLE_MIN = 0.3       # floor in sharp turns
THROTTLE_PER_M = 0.25    # throttle lost per metre of |h4|
MIN_TURN_SPEED = 4.0     # m/s: slowing for a turn never caps below this
BRAKE_PER_M_S = 0.5      # brake per m/s above the turn's cap


def steering_from_waypoint(v1: float, h1: float, max_steering_deg: float = MAX_STEERING_DEG,
                           gain: float = 1.0) -> float:
    """Controls.steering in [-1, 1] (positive right) towards the waypoint
    (v1 forward, h1 right, metres): gain * atan2(h1, v1) / max wheel angle,
    clamped. v1 <= 0: -1, 0 or +1 by the sign of h1."""
    if max_steering_deg <= 0:
        raise ValueError("steering_from_waypoint: max_steering_deg must be positive, got %r" % max_steering_deg)
    if v1 <= 0:
        return float((h1 > 0) - (h1 < 0))
    steering = gain * math.atan2(h1, v1) / math.radians(max_steering_deg)
    return max(-1.0, min(1.0, steering))


def throttle_from_waypoint(h4: float, t_max: float = THROTTLE_MAX, t_min: float = THROTTLE_MIN,
                           k: float = THROTTLE_PER_M, speed: Optional[float] = None,
                           max_speed: Optional[float] = None) -> float:
    """Controls.throttle in [0, 1]: clip(t_max - k * |h4|, t_min, t_max);
    0 when both `speed` and `max_speed` (m/s) are given and speed >= max_speed."""
    if not 0 <= t_min <= t_max <= 1:
        raise ValueError("throttle_from_waypoint: need 0 <= t_min <= t_max <= 1, got %r, %r" % (t_min, t_max))
    if speed is not None and max_speed is not None and speed >= max_speed:
        return 0.0
    return max(t_min, min(t_max, t_max - k * abs(h4)))


def turn_speed_cap(h4: float, max_speed: float, slowdown: float) -> float:
    """m/s: `max_speed` lowered by `slowdown` m/s per metre of |h4| (the
    turn 8 m ahead), not below min(MIN_TURN_SPEED, max_speed)."""
    if slowdown < 0:
        raise ValueError("turn_speed_cap: slowdown must be >= 0, got %r" % slowdown)
    return max(min(MIN_TURN_SPEED, max_speed), max_speed - slowdown * abs(h4))


def bend_curvature(w: Sequence[float]) -> float:
    """Signed curvature (1/m, positive bending right) of the circle through
    waypoints 1-3 of v1 h1 ... v4 h4 (Menger curvature: 4 x the triangle's
    area over the product of its sides); 0 when two of them coincide."""
    ax, ay = w[2] - w[0], w[3] - w[1]
    bx, by = w[4] - w[0], w[5] - w[1]
    cross = ax * by - ay * bx
    cx, cy = w[4] - w[2], w[5] - w[3]
    sides = math.sqrt(ax * ax + ay * ay) * math.sqrt(bx * bx + by * by) * math.sqrt(cx * cx + cy * cy)
    if sides == 0:
        return 0.0
    return 2 * cross / sides


def bend_shift(w: Sequence[float], v: float, h: float, bend: float, bend_limit: Optional[float] = None) -> float:
    """Metres to the right that the bend correction moves the aim point (v, h):
    -bend * kappa * (v^2 + h^2) / 2, or 0 when |h4| > bend_limit."""
    if bend_limit is not None and abs(w[7]) > bend_limit:
        return 0.0
    return -(bend * bend_curvature(w) * (v * v + h * h) / 2.0)


def controls_from_waypoints(waypoints: Sequence[float], speed: Optional[float] = None,
                            max_speed: Optional[float] = None, max_steering_deg: float = MAX_STEERING_DEG,
                            gain: float = 1.0, t_max: float = THROTTLE_MAX, t_min: float = THROTTLE_MIN,
                            k: float = THROTTLE_PER_M, steer_waypoint: int = 1,
                            slowdown: float = 0.0, bend: float = 0.0,
                            bend_limit: Optional[float] = None) -> Tuple[float, float, float]:
    """(steering, throttle, brake) for Client.SendControls from the 8
    numbers v1 h1 v2 h2 v3 h3 v4 h4 (e.g. the network's output); brake 0
    unless `slowdown` > 0 (with `speed` and `max_speed`), which lowers the
    cap for a turn ahead and brakes down to it (turn_speed_cap).
    steer_waypoint: which waypoint the steering aims at (1, the paper's
    rule, ... 4); a farther one averages out a noisy first prediction at
    the cost of cutting tight corners, which `bend` (with `bend_limit`)
    corrects (bend_shift)."""
    w = [float(x) for x in waypoints]
    if len(w) != 8:
        raise ValueError("controls_from_waypoints: expected 8 numbers v1 h1 ... v4 h4, got %d" % len(w))
    if not 1 <= steer_waypoint <= 4:
        raise ValueError("controls_from_waypoints: steer_waypoint must be 1 ... 4, got %r" % steer_waypoint)
    v, h = aim_point(w, steer_waypoint)
    if bend:
        h += bend_shift(w, v, h, bend, bend_limit)
    steering = steering_from_waypoint(v, h, max_steering_deg, gain)
    brake = 0.0
    if slowdown and max_speed is not None:
        max_speed = turn_speed_cap(w[7], max_speed, slowdown)
        if speed is not None and speed > max_speed:
            brake = min(1.0, BRAKE_PER_M_S * (speed - max_speed))
    throttle = throttle_from_waypoint(w[7], t_max, t_min, k, speed, max_speed)
    return steering, throttle, brake


def aim_point(w: Sequence[float], steer_waypoint: float) -> Tuple[float, float]:
    """(v, h) steered at: waypoint `steer_waypoint` (1 ... 4), or between two
    waypoints for a fraction (1.5: halfway from the 2 m to the 4 m one,
    linearly); a whole number gives the waypoint itself, exactly."""
    k = int(steer_waypoint) - 1
    if k == 3:
        return w[6], w[7]
    f = steer_waypoint - 1 - k
    if f == 0:
        return w[2 * k], w[2 * k + 1]
    return (w[2 * k] + f * (w[2 * k + 2] - w[2 * k]), w[2 * k + 1] + f * (w[2 * k + 3] - w[2 * k + 1]))


@dataclass(frozen=True)
class Controller:
    """How a policy's waypoints become controls; the defaults are the
    paper's rule. steer_waypoint: the waypoint steered at (1 ... 4); gain:
    multiplies the steering angle; slowdown: turn_speed_cap's (0: off);
    bend, bend_limit: bend_shift's (0: off; None: no limit)."""
    steer_waypoint: int = 1
    gain: float = 1.0
    slowdown: float = 0.0
    bend: float = 0.0
    bend_limit: Optional[float] = None

    def __post_init__(self):
        if not 1 <= self.steer_waypoint <= 4:
            raise ValueError("Controller: steer_waypoint must be 1 ... 4, got %r" % self.steer_waypoint)
        if not self.gain > 0:
            raise ValueError("Controller: gain must be positive, got %r" % self.gain)
        if not self.slowdown >= 0:
            raise ValueError("Controller: slowdown must be >= 0, got %r" % self.slowdown)
        if not 0 <= self.bend <= 1:
            raise ValueError("Controller: bend must be 0 ... 1, got %r" % self.bend)
        if self.bend_limit is not None and not self.bend_limit > 0:
            raise ValueError("Controller: bend_limit must be positive, got %r" % self.bend_limit)

    def controls(self, waypoints: Sequence[float], speed: Optional[float] = None,
                 max_speed: Optional[float] = None) -> Tuple[float, float, float]:
        """(steering, throttle, brake): controls_from_waypoints with these choices."""
        return controls_from_waypoints(waypoints, speed=speed, max_speed=max_speed, gain=self.gain,
                                       steer_waypoint=self.steer_waypoint, slowdown=self.slowdown,
                                       bend=self.bend, bend_limit=self.bend_limit)

    def settings(self) -> dict:
        """The keys a report records them under."""
        return {"steer_waypoint": self.steer_waypoint, "steer_gain": self.gain, "slowdown": self.slowdown,
                "bend_correction": self.bend, "bend_limit_m": self.bend_limit}


def add_arguments(parser, steer_waypoint: Optional[int] = None) -> None:
    """The Controller's command-line options (read back by from_arguments).
    Unset ones stay None, so a model card (sim4cv.driving_card.apply) can
    fill them; from_arguments fills what is still unset with the defaults."""
    parser.add_argument("--steer-waypoint", type=_whole_or_fraction, default=steer_waypoint,
                        help="the waypoint the steering aims at, 1 ... 4 (1: the paper's rule; 1.5: halfway between "
                             "the first and the second; default: the model card's, else %s)" % (steer_waypoint or 1))
    parser.add_argument("--steer-gain", type=float, default=None,
                        help="multiplies the steering angle (default: the model card's, else 1, the paper's rule)")
    parser.add_argument("--turn-slowdown", type=float, default=None,
                        help="m/s of speed cap lost per metre of |h4|, braking down to it (default: the model "
                             "card's, else 0: the paper's throttle)")
    parser.add_argument("--bend-correction", type=float, default=None,
                        help="0 ... 1: the aim point moved that fraction of the chord's offset towards the bend's "
                             "outside (default: the model card's, else 0: the paper's rule)")
    parser.add_argument("--bend-limit", type=float, default=None,
                        help="m: no bend correction while |h4| exceeds this (default: the model card's, else none)")


def _whole_or_fraction(text: str):
    """--steer-waypoint's value: an int when whole (reports keep 2, not 2.0)."""
    value = float(text)
    return int(value) if value.is_integer() else value


def from_arguments(parser, args) -> Controller:
    """The Controller of add_arguments' options (unset ones: Controller's
    defaults); a bad one ends the command through parser.error (exit
    status 2) with Controller's message."""
    default = Controller()
    try:
        return Controller(default.steer_waypoint if args.steer_waypoint is None else args.steer_waypoint,
                          default.gain if args.steer_gain is None else args.steer_gain,
                          default.slowdown if args.turn_slowdown is None else args.turn_slowdown,
                          default.bend if args.bend_correction is None else args.bend_correction,
                          args.bend_limit)
    except ValueError as e:
        parser.error(str(e))
