"""Closed-loop evaluation of a driving policy (docs/driving.md, "Closed-loop
evaluation"): the car drives one lap of every route of the chosen maps
under the policy, in a lockstep sim4cvd of its own per map, and its
distance to the ideal path (the right-lane centre of its route, exact:
sim4cv.driving_dataset.RoutePath) is recorded every frame.

    python3 -m sim4cv.driving evaluate --model OUT/model.onnx --maps test --out DIR
    python3 -m sim4cv.driving evaluate --policy reference --maps test --out DIR

Policies: `network` (a model.pt of sim4cv.driving_train, run by torch, or a
model.onnx run by OpenCV's DNN, as the C++ client does) and `reference`
(the true waypoints of the route: separates the controller's error from
the network's). Both go through the same controller (sim4cv.driving_control).

A run ends after one lap, when the car is more than OFF_ROAD_M from the
lane centre (it left the road: `completed` false), or after a time limit.
"""

import csv
import json
import math
import os
import time
from typing import Dict, List, Optional, Sequence

import numpy as np

from . import driving_control as dc
from . import driving_labels as dl
from . import driving_metrics as dm
from . import driving_obstacles as dob
from .driving_dataset import CAMERA_SETTINGS, WAYPOINT_COUNT, WAYPOINT_STEP_M, RoutePath, parse_map, resolve_maps
from .driving_route import RoadGrid, RouteGoals

EGO, EGO_CAMERA = "ego", "ego_cam"
OFF_ROAD_M = 4.0          # beyond the road's right edge or into the far side of the other lane
DEFAULT_SPEED = 8.0       # m/s, the controller's speed cap
TIME_MARGIN_S = 30.0      # a run may take lap / (speed / 2) + this before it is stopped
TRANSPORTS = ("tcp", "udp")
TAKEBACK_M = 0.2          # drive_route's takeover: the policy drives again once this close to the ideal path


class EvalError(RuntimeError):
    """The evaluation cannot run (a missing or malformed model, no maps); the message says why."""


def yaw_of(orientation) -> float:
    """Heading (rad, counter-clockwise from east) of a (w, x, y, z) quaternion."""
    w, x, y, z = orientation
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def car_pose(frame, car_id: int):
    """(x, y, yaw rad, ground speed m/s) of entity car_id in a frame's state
    (subscribed with_state); None if the frame holds no such entity."""
    pose = next((e for e in frame.entities if e.id == car_id), None)
    if pose is None:
        return None
    v = pose.linear_velocity
    return pose.position[0], pose.position[1], yaw_of(pose.orientation), math.hypot(v[0], v[1])


# ---------------------------------------------------------------------------
# Policies: waypoints (v1 h1 ... v4 h4, h positive right) from a frame

class ReferencePolicy:
    """The route's true waypoints 2, 4, 6, 8 m ahead of the car's nearest
    lane point, encoded for the car's pose: what a perfect network predicts."""
    name = "reference"

    def waypoints(self, rgb, pose, progress) -> List[float]:
        x, y, yaw = pose
        points = [progress.path.point(progress.u + WAYPOINT_STEP_M * k)[:2] for k in range(1, WAYPOINT_COUNT + 1)]
        return [c for vh in dl.encode(x, y, yaw, points) for c in vh]


class NetworkPolicy:
    """A trained WaypointNet: OUT/model.pt (torch) or OUT/model.onnx (OpenCV
    DNN). The camera image is shrunk to the model's size (INTER_AREA, as in
    training). lane="left" mirrors the image and the predicted h (the
    paper's lane-change trick: the right-lane network drives the left lane)."""
    name = "network"

    def __init__(self, path: str, goal: float = 0.0, lane: str = "right"):
        import cv2
        self.cv2 = cv2
        self.goal, self.lane, self.path = float(goal), lane, path
        if not os.path.isfile(path):
            raise EvalError("model file %s does not exist" % path)
        if os.path.getsize(path) == 0:
            raise EvalError("model file %s is empty (0 bytes): an interrupted copy or export?" % path)
        if path.endswith(".onnx"):
            self.height, self.width, self.run, self.use_goal = _load_onnx(path)
        elif path.endswith(".pt"):
            self.height, self.width, self.run, self.use_goal = _load_torch(path)
        else:
            raise EvalError("model file %s: expected a .pt (sim4cv.driving_train) or .onnx file" % path)

    def waypoints(self, rgb, pose, progress) -> List[float]:
        image = rgb
        if image.shape[0] != self.height or image.shape[1] != self.width:
            image = self.cv2.resize(image, (self.width, self.height), interpolation=self.cv2.INTER_AREA)
        goal = self.goal
        if self.lane == "left":  # a left turn in the mirrored image is a right one
            image, goal = image[:, ::-1], -goal
        out = [float(v) for v in self.run(np.ascontiguousarray(image), goal)]
        if self.lane == "left":
            out = [-v if i % 2 else v for i, v in enumerate(out)]
        return out


def _load_onnx(path: str):
    from .driving_net import load_onnx_with_opencv
    try:
        import onnx
        model = onnx.load(path)
    except Exception as e:  # noqa: BLE001 - any parse failure is a bad model file
        raise EvalError("model file %s is not a readable ONNX model (truncated or not ONNX): %s" % (path, e)) from None
    if not model.graph.input or not model.graph.output:
        raise EvalError("model file %s is not a readable ONNX model: it holds no graph inputs or outputs "
                        "(truncated, or not ONNX)" % path)
    dims = [d.dim_value for d in model.graph.input[0].type.tensor_type.shape.dim]
    outs = [d.dim_value for d in model.graph.output[0].type.tensor_type.shape.dim]
    if len(dims) != 4 or dims[:2] != [1, 3] or outs != [1, 8]:
        raise EvalError("model file %s: expected input [1, 3, H, W] and output [1, 8] (v1 h1 ... v4 h4), found "
                        "input %s and output %s" % (path, dims, outs))
    try:
        run = load_onnx_with_opencv(path)
    except Exception as e:  # noqa: BLE001 - OpenCV's own parser may refuse what the onnx package read
        raise EvalError("model file %s: OpenCV's DNN cannot load it: %s" % (path, e)) from None
    return dims[2], dims[3], run, any(i.name == "goal" for i in model.graph.input)


def _load_torch(path: str):
    import torch
    from .driving_train import load_model
    try:
        model = load_model(path)
    except Exception as e:  # noqa: BLE001
        raise EvalError("model file %s is not a sim4cv.driving_train model.pt: %s" % (path, e)) from None
    model.eval()

    def run(image, goal):
        x = torch.from_numpy(image).permute(2, 0, 1).float().unsqueeze(0)
        g = torch.tensor([[goal]], dtype=torch.float32) if model.use_goal else None
        with torch.no_grad():  # only here: turning gradients off globally would break training in this process
            return model(x, g)[0].numpy() if g is not None else model(x)[0].numpy()
    return model.height, model.width, run, model.use_goal


def check_waypoints(waypoints: Sequence[float], policy, where: str) -> None:
    """Stops the run (EvalError naming the model and `where`) when a policy
    gives a waypoint that is NaN or infinite: the controller would turn it
    into full lock, and the lap would be scored as if the model had driven."""
    if all(math.isfinite(v) for v in waypoints):
        return
    who = "model %s" % policy.path if getattr(policy, "path", None) else "policy %s" % policy.name
    raise EvalError("%s gave non-finite waypoints [%s] at %s: stopped"
                    % (who, ", ".join("%g" % v for v in waypoints), where))


# ---------------------------------------------------------------------------
# One route

def drive_route(client, info: dict, route: str, policy, speed: float, frame_hz: float, log=print,
                obstacles: int = 0, seed: int = 0, controller: dc.Controller = dc.Controller(),
                takeover_m: float = 0.0):
    """Drives one lap of `route` under `policy` (with `obstacles` parked cars
    to pass, placed as the dataset places them); returns (run dict, rows, deviations).
    takeover_m > 0: the reference policy drives from that far off the ideal
    path until the car is back within TAKEBACK_M and not passing an obstacle
    (collecting a policy's mistakes and the recoveries from them:
    sim4cv.driving_dagger)."""
    lane = RoutePath(info, route)
    # A policy driving the left lane (the mirror trick) is scored against the left lane's centre.
    offset = dob.LANE_SHIFT_M if getattr(policy, "lane", "right") == "left" else 0.0
    path = dob.ShiftedPath.placed(lane, obstacles, seed, info["name"], offset)
    parked = []
    for k, (ox, oy, oyaw) in enumerate(path.obstacle_poses()):
        client.spawn("car", dob.OBSTACLE_NAME % k, ox, oy, 0.0, math.degrees(oyaw))
        parked.append(("car", ox, oy, math.degrees(oyaw)))
    x0, y0, yaw0 = path.point(0.0)
    ego = client.spawn("car", EGO, x0, y0, 0.0, math.degrees(yaw0))
    cam = CAMERA_SETTINGS  # the geometry of the map car's car_front, mounted on the ego car
    client.add_camera(EGO_CAMERA, mounted_on=EGO, width=cam["width"], height=cam["height"],
                      fov_y_deg=cam["fov_y_deg"], pitch_down_deg=cam["pitch_down_deg"],
                      offset=(cam["forward_m"], 0.0, cam["above_body_m"]))
    client.subscribe(EGO_CAMERA, ["rgb"], "lockstep", with_state=True)
    progress = dm.Progress(path, 0.0)  # u along the route; its points are the ideal path's
    goals = RouteNavigation(info, route) if getattr(policy, "use_goal", False) else None
    collisions = dm.Collisions(info["objects"] + parked)
    lap = path.length if path.closed else path.length - WAYPOINT_STEP_M * WAYPOINT_COUNT
    limit_s = lap / (speed / 2.0) + TIME_MARGIN_S
    rows, deviations = [], []
    completed, off_road = False, False
    frame = client.step_and_receive(timeout=30.0)
    t0 = frame.sim_time
    infer_s = 0.0
    expert, taking_over, takeovers, expert_frames = (ReferencePolicy() if takeover_m > 0 else None), False, 0, 0
    while True:
        x, y, yaw, car_speed = car_pose(frame, ego)
        lane_deviation = progress.update(x, y)
        deviation = path.deviation(progress.u, lane_deviation)
        hit = collisions.update(x, y, yaw)
        deviations.append(deviation)
        if progress.u >= lap:
            completed = True
        elif abs(deviation) > OFF_ROAD_M:
            off_road = True
        t = frame.sim_time - t0
        if completed or off_road or t > limit_s:
            rows.append([round(t, 4), round(x, 3), round(y, 3), round(math.degrees(yaw), 2), round(progress.u, 3),
                         round(deviation, 4), round(car_speed, 3), "", "", "", hit])
            break
        if goals is not None:  # the route's way at the junction ahead, as a navigation system tells it
            policy.goal = goals.goal(progress.u)
        if expert is not None:
            if not taking_over and abs(deviation) > takeover_m:
                taking_over, takeovers = True, takeovers + 1
            elif taking_over and abs(deviation) < TAKEBACK_M and not path.passing(progress.u):
                taking_over = False  # not in the middle of passing an obstacle: beside it, a hand-back hits it
            expert_frames += taking_over
        driver = expert if taking_over else policy
        started = time.perf_counter()
        w = driver.waypoints(frame.image("rgb"), (x, y, yaw), progress)
        infer_s += time.perf_counter() - started
        check_waypoints(w, driver, "frame %d (%.2f s) of route %s on %s" % (frame.frame_id, t, route, info["name"]))
        steering, throttle, brake = controller.controls(w, speed=car_speed, max_speed=speed)
        client.send_controls(ego, steering, throttle, brake)
        rows.append([round(t, 4), round(x, 3), round(y, 3), round(math.degrees(yaw), 2), round(progress.u, 3),
                     round(deviation, 4), round(car_speed, 3), round(steering, 4), round(throttle, 4),
                     round(brake, 4), hit])
        previous_id, frame = frame.frame_id, client.step_and_receive(timeout=30.0)
        if frame.frame_id != previous_id + 1:  # over UDP a lost frame is skipped: the lap would not be lockstep
            raise EvalError("frame %d came after frame %d on route %s of %s: a frame was lost (%s), so this lap "
                            "is not the lockstep lap; run it again" % (frame.frame_id, previous_id, route,
                                                                       info["name"], client.transport))
    run = dm.score(deviations, min(progress.u, lap), collisions.count)
    run.update(completed=completed, left_road=off_road, route=route, lap_m=round(lap, 2), obstacles=len(parked),
               sim_seconds=round(rows[-1][0], 3), policy_ms=round(1000.0 * infer_s / max(len(rows), 1), 3))
    if expert is not None:
        run.update(takeovers=takeovers, expert_frames=expert_frames)
    log("  route %s: %s, %.0f m, mean deviation %.1f cm, within 25 cm %.1f%%, departures %d, collisions %d"
        % (route, "completed" if completed else ("left the road" if off_road else "timed out"), run["distance_m"],
           run["mean_deviation_cm"] or 0.0, 100.0 * (run["within_25cm"] or 0.0), run["lane_departures"],
           run["collisions"]))
    return run, rows, deviations, path


class RouteNavigation:
    """The goal a navigation system gives a goal model on a known route:
    within driving_guided.GOAL_BEFORE_M before a junction of the route, and
    in it, the direction the route takes there (-1 left, 0 straight, +1
    right); elsewhere 0 (the maps' routes turn at junctions where the road
    also goes on, so the image alone cannot tell the way)."""

    def __init__(self, info: dict, route: str):
        self.goals = RouteGoals(info, RoadGrid.from_map(info["path"]), route)

    def goal(self, u: float) -> float:
        hit = self.goals.junction_at(u)
        return float(hit[0]) if hit is not None else 0.0


ROW_COLUMNS = ["t", "x", "y", "yaw_deg", "u", "deviation_m", "speed", "steering", "throttle", "brake", "collision"]


# ---------------------------------------------------------------------------
# A whole evaluation

def evaluate(policy, maps: Sequence[str], surroundings: Sequence[str], out: str, speed: float = DEFAULT_SPEED,
             conditions: str = "", frame_hz: float = 30.0, log=print, label: str = "", obstacles: int = 0,
             seed: int = 0, controller: dc.Controller = dc.Controller(), takeover_m: float = 0.0,
             settings_from: Optional[Dict[str, str]] = None, transport: str = "tcp") -> dict:
    """Drives every route of every map; writes out/driving.json, out/runs/*.csv
    and the plots; returns driving.json's content. takeover_m: drive_route's.
    settings_from: where each controller setting came from (flag, model card
    or default: sim4cv.driving_card.apply), recorded in the report.
    transport: "tcp" or "udp" (frames, Steps and Controls on one UDP socket,
    still lockstep: the same laps, frame for frame)."""
    if transport not in TRANSPORTS:
        raise EvalError("transport %r: one of %s" % (transport, ", ".join(TRANSPORTS)))
    resolved = resolve_maps(maps, surroundings)
    infos = [parse_map(path) for path, _ in resolved]  # every map read before OUT is made: a refusal leaves none
    made = [d for d in (out, os.path.join(out, "runs")) if not os.path.isdir(d)]
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    try:
        return _evaluate_maps(policy, resolved, infos, out, speed, conditions, frame_hz, log, label, obstacles,
                              seed, controller, takeover_m, settings_from, transport)
    except EvalError:
        for d in reversed(made):  # a run stopped before its first lap was written leaves no empty folder
            if os.path.isdir(d) and not os.listdir(d):
                os.rmdir(d)
        raise


def _evaluate_maps(policy, resolved, infos, out, speed, conditions, frame_hz, log, label, obstacles, seed,
                   controller, takeover_m, settings_from, transport) -> dict:
    import sim4cv
    from .daemon import OwnDaemon
    from . import driving_plots

    report = {"settings": {"policy": policy.name, "model": getattr(policy, "path", None), "label": label,
                           "maps": [p for p, _ in resolved], "speed_m_s": speed, "conditions": conditions or "clear_noon",
                           "frame_hz": frame_hz, "off_road_m": OFF_ROAD_M,
                           "lane_departure_m": dm.LANE_DEPARTURE_M, "obstacles": obstacles, "seed": seed,
                           "takeover_m": takeover_m, **controller.settings(),
                           "settings_from": settings_from or {}, "transport": transport},
              "maps": {}}
    pooled: Dict[str, List] = {"overall": [], "desert": [], "urban": []}
    trajectories = {}
    t_start = time.monotonic()
    for (path, _), info in zip(resolved, infos):
        name = info["name"]
        log("%s (%s)" % (name, info["surroundings"]))
        flags = ["--map", path, "--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0",
                 "--frame-hz", str(int(frame_hz))]
        if conditions:
            flags += ["--conditions", conditions]
        runs, map_devs = {}, []
        for route in info["routes"]:
            # a daemon per route: the ego car and its camera start from a clean world
            with OwnDaemon(flags, mode="lockstep") as daemon, \
                    sim4cv.connect(_address(daemon, transport), name="driving_eval", timeout=30.0) as client:
                for entity in client.get_world().entities:
                    if entity.name in ("car", "uav"):  # the map's own car and the UAV filming it
                        client.remove(entity.id)
                run, rows, deviations, ideal = drive_route(client, info, route, policy, speed, frame_hz, log,
                                                           obstacles, seed, controller, takeover_m)
            runs[route] = run
            map_devs.append(deviations)
            _write_rows(os.path.join(out, "runs", "%s_%s.csv" % (name, route)), rows)
            trajectories[(name, route)] = (ideal, route, rows)
            for key in ("overall", info["surroundings"]):
                if key in pooled:
                    pooled[key].append((run, deviations))
        report["maps"][name] = {"surroundings": info["surroundings"], "routes": runs,
                                "score": dm.pooled(list(runs.values()), map_devs)}
    for key, entries in pooled.items():
        if entries:
            report[key if key == "overall" else "surroundings_" + key] = dm.pooled(
                [r for r, _ in entries], [d for _, d in entries])
    report["histogram"] = {key: dm.cumulative_histogram([v for _, d in entries for v in d])[1]
                           for key, entries in pooled.items() if entries}
    report["histogram_edges_m"] = dm.cumulative_histogram([])[0]
    report["paper"] = dm.PAPER
    report["seconds"] = round(time.monotonic() - t_start, 1)
    with open(os.path.join(out, "driving.json"), "w") as f:
        json.dump(report, f, indent=1)
    driving_plots.histogram(report, os.path.join(out, "histogram.png"))
    driving_plots.trajectories(trajectories, os.path.join(out, "trajectories"))
    o = report.get("overall", {})
    log("overall: %d runs, %d completed, mean deviation %s cm, within 25 cm %s, departures %d, collisions %d (%.0f s)"
        % (o.get("runs", 0), o.get("completed", 0), o.get("mean_deviation_cm"), o.get("within_25cm"),
           o.get("lane_departures", 0), o.get("collisions", 0), report["seconds"]))
    return report


def _address(daemon, transport: str) -> str:
    """The evaluation's one connection to its daemon: TCP, or the daemon's UDP port."""
    if transport == "tcp":
        return daemon.address
    if not daemon.fields.get("udp") or daemon.fields["udp"] == "-1":
        raise EvalError("the daemon serves no UDP port (its listening line: %s)" % daemon.fields)
    return "udp://127.0.0.1:%s" % daemon.fields["udp"]


def _write_rows(path: str, rows) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(ROW_COLUMNS)
        w.writerows(rows)


def evaluate_conditions(policy, maps: Sequence[str], surroundings: Sequence[str], out: str,
                        presets: Sequence[str], speed: float = DEFAULT_SPEED, frame_hz: float = 30.0,
                        log=print, **settings) -> dict:
    """The same evaluation under each weather/time-of-day preset, into
    out/<preset>/; out/conditions.json and out/conditions.md compare them
    (how far the score falls out of the training distribution). `settings`:
    evaluate's other keywords (controller, obstacles, seed)."""
    rows = {}
    for preset in presets:
        log("== conditions %s" % preset)
        report = evaluate(policy, maps, surroundings, os.path.join(out, preset), speed, preset, frame_hz, log,
                          **settings)
        rows[preset] = {key: report.get(key) for key in ("overall", "surroundings_desert", "surroundings_urban")}
    with open(os.path.join(out, "conditions.json"), "w") as f:
        json.dump({"presets": rows, "model": getattr(policy, "path", None), "policy": policy.name}, f, indent=1)
    lines = ["| conditions | laps completed | mean deviation (cm) | within 25 cm | within 1 m | lane departures |",
             "|---|---|---|---|---|---|"]
    for preset, r in rows.items():
        o = r["overall"]
        lines.append("| %s | %d/%d | %s | %s | %s | %d |" % (
            preset, o["completed"], o["runs"], _fmt(o["mean_deviation_cm"], "%.2f"), _fmt(o["within_25cm"], "%.3f"),
            _fmt(o["within_1m"], "%.3f"), o["lane_departures"]))
    with open(os.path.join(out, "conditions.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    log("\n".join(lines))
    return rows


def _fmt(value, pattern: str) -> str:
    return "–" if value is None else pattern % value
