"""Tracking in the loop (docs/tracking.md, "Online evaluation"): UAVs follow
a car on a map, each steered by the boxes of its own tracker.

    from sim4cv.tracking import Session, run_session
    results = run_session(Session(map="tracking/hard_urban", speed=8, trackers=["gt", "opencv:kcf"],
                                  mode="realtime", seconds=60), out_dir="runs/one")

The session starts its own sim4cvd (or uses `address`), spawns one UAV per
tracker with a camera like the scene's UAV camera (the first tracker flies
the scene's UAV; the others follow the target 1.5 m above each other until
their trackers start), and runs each tracker in its own process on its own
connection, which orders its UAV to track as the tracker starts
(CommandUav.track: the daemon's servo steers it by the newest box that
tracker sent). A tracker is initialised with the
target's ground-truth box of its first frame, then gets frames and answers
with a box per frame it processed. In `lockstep` mode the simulation waits
for every tracker (the offline-equivalent run); in `realtime` mode sim time
follows the wall clock, a tracker asks for the newest frame when it is
ready (DELIVERY_ON_REQUEST) and every frame it was too slow for is skipped
and counted. `delay_ms` adds a fixed delay to every answer.

Lost target: the target has no ground-truth box with visibility of at least
`min_visibility` in the UAV's camera for longer than `lost_after_s` seconds
of sim time; that UAV's run then ends with the distance covered.
"""

import csv
import math
import multiprocessing
import os
import statistics
import time
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional

from . import strict_json
from .daemon import REPO_ROOT, OwnDaemon

EXTRA_UAV_CLIMB_M = 1.5
SETTLE_S = 30.0  # sim seconds a UAV may take to bring the target into view before its tracker starts
STEADY_S = 1.0   # ... and hold it steady in view this long (a tracker starts on a settled view)
STEADY_PX = 2.0  # box centre motion per frame that counts as steady
FRAME_HEADER = ["frame_id", "sim_time", "box_x", "box_y", "box_w", "box_h", "gt_x", "gt_y", "gt_w", "gt_h",
                "gt_visibility", "update_ms", "uav_x", "uav_y", "uav_z", "target_x", "target_y", "target_z"]


@dataclass
class Session:
    """One run: a map, a target speed, one tracker per UAV, and the rules."""
    map: str = "tracking/easy_urban"    # under scenes/, without .map; "" for the default scene
    speed: float = 6.0                  # m/s, the target car's set speed
    trackers: List[str] = field(default_factory=lambda: ["gt"])  # one UAV each (sim4cv.trackers)
    mode: str = "lockstep"              # or "realtime"
    fps: float = 30.0                   # camera frame rate: 15, 30 or 60
    delay_ms: float = 0.0               # added to every tracker answer
    seconds: float = 60.0               # sim time the session lasts
    target: str = "car"                 # or "pedestrian": a walker on the car's route at `speed` (car removed)
    lost_after_s: float = 1.0           # the target unseen this long: lost
    min_visibility: float = 0.1         # a box with less visibility counts as unseen
    conditions: str = ""                # a weather/time-of-day preset (docs/protocol.md); "": the daemon's
    log: bool = True                    # write the daemon's run log (trajectories)
    tracker_timeout_s: float = 30.0     # each tracker call (python:, trax:, octave:) may take this long; then killed

    def daemon_args(self, log_path: Optional[str]) -> List[str]:
        args = ["--frame-hz", "%g" % self.fps, "--car-speed", "%g" % self.speed, "--log-level", "warning"]
        if self.map:
            args += ["--map", os.path.join(REPO_ROOT, "scenes", self.map + ".map")]
        if self.conditions:
            args += ["--conditions", self.conditions]
        if log_path:
            args += ["--log", log_path]
        return args


def _world_ids(client, needed=("car", "uav")):
    world = client.get_world()
    ids = {e.name: e.id for e in world.entities}
    if any(name not in ids for name in needed):
        raise ValueError("the world has no %s to track with (entities: %s)"
                         % (" and ".join("'%s'" % n for n in needed), ", ".join(ids)))
    return world, ids


def _target(client, session: Session) -> int:
    """The target's id: the map's car, or a walker that replaces it on its route."""
    world, ids = _world_ids(client)
    if session.target == "car":
        return ids["car"]
    if session.target != "pedestrian":
        raise ValueError("Session.target is 'car' or 'pedestrian', not %r" % (session.target,))
    if not world.routes:
        raise ValueError("the world has no route for a pedestrian to walk")
    walker = client.spawn("pedestrian", "walker", 0, 0, 0)
    client.set_route(walker, world.routes[0], min(session.speed, 10.0))
    client.remove(ids["car"])
    client.uav_follow(ids["uav"], walker)
    return walker


def _add_uavs(client, count: int, target: int) -> List[tuple]:
    """(uav id, camera) for `count` UAVs: the scene's, then new ones beside
    it, each following the target (1.5 m higher than the one before, so no two
    share a station) until its tracker starts."""
    world, ids = _world_ids(client, ("uav",))
    uavs = [(ids["uav"], "uav")]
    state = client.get_state()
    first = next(e for e in state.entities if e.id == ids["uav"])
    for k in range(1, count):
        name = "uav_%d" % k
        uav = client.spawn("uav", name, first.position.x + 3.0 * k, first.position.y + 3.0 * k,
                           first.position.z + EXTRA_UAV_CLIMB_M * k)
        client.add_camera(name + "_cam", mounted_on=name, pitch_down_deg=60.0, gimbal=True)
        client.uav_follow(uav, target, altitude=15.0 + EXTRA_UAV_CLIMB_M * k)
        uavs.append((uav, name + "_cam"))
    return uavs


def _settled(frame, truth, last) -> bool:
    """Whether a UAV following the target has it well in view to start a
    tracker on: unoccluded, its centre in the middle third of the image and
    moving less than STEADY_PX since the last frame."""
    if truth is None or last is None or truth.visibility < 0.9:
        return False
    cx, cy = truth.x + truth.width / 2, truth.y + truth.height / 2
    moved = math.hypot(cx - last.x - last.width / 2, cy - last.y - last.height / 2)
    return (abs(cx - frame.width / 2) < frame.width / 6 and abs(cy - frame.height / 2) < frame.height / 6
            and moved < STEADY_PX)


def _box_or_nan(box):
    return list(box) if box is not None else [math.nan] * 4


def _centre_error(a, b):
    return math.hypot(a[0] + a[2] / 2 - b[0] - b[2] / 2, a[1] + a[3] / 2 - b[1] - b[3] / 2)


def _worker(address, camera, uav_id, target_id, spec, session_dict, barrier, out_csv, result_queue):
    """One UAV's tracker on its own connection (a process of its own)."""
    from . import connect
    from .errors import ServerError
    from .trackers import make_tracker
    session = Session(**session_dict)
    result = {"tracker": spec, "uav": uav_id, "camera": camera, "lost": False, "error": ""}
    rows = []
    flown = {"frames_processed": 0, "frames_skipped": 0, "boxes_refused": 0, "seconds": 0.0, "covered_m": 0.0}
    update_s, waited = [], [False]
    tracker = None
    try:
        tracker = make_tracker(spec, target_id, timeout=session.tracker_timeout_s)
        with connect(address, name="tracker-%d" % uav_id) as client:
            delivery = "lockstep" if session.mode == "lockstep" else "on_request"
            client.subscribe(camera, ["rgb", "boxes"], delivery, with_state=True)
            waited[0] = True
            barrier.wait(120)  # every tracker subscribed: nobody steps alone
            fetch = client.step_and_receive if session.mode == "lockstep" else client.request_frame

            def get(timeout):
                """The next frame; an Error refusing one of our boxes (far outside the image, inf) is counted."""
                call = fetch
                while True:
                    try:
                        return call(timeout)
                    except ServerError as e:
                        if e.fatal or "TrackerOutput" not in e.message:
                            raise
                        flown["boxes_refused"] += 1
                        call = client.receive_frame  # the frame asked for is still coming
            frame = get(30.0)
            start, steady, last = frame.sim_time, 0.0, None
            while steady < STEADY_S:  # the UAV is at its station, the target still in the image
                previous, frame = frame, get(30.0)
                truth = frame.box(target_id)
                settled = _settled(frame, truth, last)
                steady = steady + frame.sim_time - previous.sim_time if settled else 0.0
                last = truth
                if frame.sim_time - start > SETTLE_S:
                    raise RuntimeError("the target was not well in view of %s within %g s" % (camera, SETTLE_S))
            truth = frame.box(target_id)
            start = frame.sim_time
            gt = (truth.x, truth.y, truth.width, truth.height)
            tracker.init(frame.image("rgb"), gt, frame=frame)
            client.send_tracker_output(frame.frame_id, *map(float, gt), 1.0)
            client.uav_track(uav_id, camera)  # from here on the tracker's boxes steer the UAV
            last_id, unseen_since, last_target = frame.frame_id, None, None
            while frame.sim_time - start < session.seconds:
                frame = get(30.0)
                flown["frames_skipped"] += max(0, frame.frame_id - last_id - 1)
                last_id = frame.frame_id
                flown["seconds"] = frame.sim_time - start
                t0 = time.perf_counter()
                box = tracker.update(frame.image("rgb"), frame=frame)
                update_s.append(time.perf_counter() - t0)
                if session.delay_ms > 0:
                    time.sleep(session.delay_ms / 1000.0)
                flown["frames_processed"] += 1
                if box is not None and box[2] > 0 and box[3] > 0:
                    try:
                        client.send_tracker_output(frame.frame_id, *box, 1.0)
                    except (ServerError, ValueError):
                        flown["boxes_refused"] += 1  # refused before it left: the servo keeps the last box
                truth = frame.box(target_id)
                poses = {e.id: e.position for e in frame.entities}
                target = poses.get(target_id, (math.nan,) * 3)
                if last_target is not None:
                    flown["covered_m"] += math.dist(target[:2], last_target[:2])
                last_target = target
                rows.append([frame.frame_id, frame.sim_time] + _box_or_nan(box) +
                            _box_or_nan(None if truth is None else (truth.x, truth.y, truth.width, truth.height)) +
                            [0.0 if truth is None else truth.visibility, 1000 * update_s[-1]] +
                            list(poses.get(uav_id, (math.nan,) * 3)) + list(target))
                if truth is None or truth.visibility < session.min_visibility:
                    unseen_since = frame.sim_time if unseen_since is None else unseen_since
                    if frame.sim_time - unseen_since > session.lost_after_s:
                        result["lost"] = True
                        break
                else:
                    unseen_since = None
            flown["seconds"] = frame.sim_time - start
    except Exception as e:  # reported in the results: one tracker's failure ends only its run
        result["error"] = "%s: %s" % (type(e).__name__, e)
        result["lost"] = True
        if not waited[0]:  # failed before the barrier: still pass it, so the other UAVs start and fly on
            try:
                barrier.wait(120)
            except Exception:
                pass
    finally:
        if tracker is not None:
            tracker.close()
    # what it flew counts, whether its run ended by the clock, a loss or an error
    ended = flown["seconds"]
    result.update(flown, tracker_fps=len(update_s) / sum(update_s) if update_s and sum(update_s) > 0 else math.nan,
                  completion=1.0 if not result["lost"] else
                  flown["covered_m"] / max(flown["covered_m"] + session.speed * (session.seconds - ended), 1e-9))
    with open(out_csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(FRAME_HEADER)
        w.writerows(rows)
    errors = [_centre_error(r[2:6], r[6:10]) for r in rows if not math.isnan(r[2] + r[6])]
    distances = [math.dist(r[12:14], r[15:17]) for r in rows if not math.isnan(r[12] + r[15])]
    result.update(mean_center_error_px=statistics.fmean(errors) if errors else math.nan,
                  median_center_error_px=statistics.median(errors) if errors else math.nan,
                  mean_distance_m=statistics.fmean(distances) if distances else math.nan)
    result_queue.put(result)


def _collect(workers, results) -> List[Dict]:
    """Each worker's result; a worker that died without one (killed, or a
    script without a __main__ guard under the spawn start method) gets an
    error result instead of a wait for ever."""
    import queue
    collected = []
    while len(collected) < len(workers):
        try:
            collected.append(results.get(timeout=1.0))
        except queue.Empty:
            if not any(w.is_alive() for w in workers):
                try:
                    collected.append(results.get(timeout=1.0))
                    continue
                except queue.Empty:
                    break
    for w in workers:
        w.join(30)
    return collected


def run_session(session: Session, out_dir: str, address: Optional[str] = None) -> Dict:
    """Runs `session` and writes into `out_dir`: frames_<k>.csv per UAV (one
    row per processed frame), run.s4log (the daemon's run log, if its own),
    session.json (the session and a result per UAV). Returns what
    session.json holds."""
    if session.mode == "lockstep" and session.delay_ms > 0:
        raise ValueError("delay_ms %g with mode lockstep: the simulation waits for every answer, so a delay "
                         "changes nothing it measures; use mode realtime for a latency sweep" % session.delay_ms)
    os.makedirs(out_dir, exist_ok=True)
    log_path = os.path.join(out_dir, "run.s4log") if session.log and address is None else None
    daemon = None
    if address is None:
        daemon = OwnDaemon(session.daemon_args(log_path), mode=session.mode)
        address = daemon.address
    context = multiprocessing.get_context("spawn")
    try:
        from . import connect
        with connect(address, name="session") as control:
            target = _target(control, session)
            uavs = _add_uavs(control, len(session.trackers), target)
            barrier = context.Barrier(len(uavs) + 1)
            results = context.Queue()
            workers = [context.Process(target=_worker, args=(address, camera, uav, target, spec, asdict(session),
                                                            barrier, os.path.join(out_dir, "frames_%d.csv" % k),
                                                            results))
                       for k, ((uav, camera), spec) in enumerate(zip(uavs, session.trackers))]
            for w in workers:
                w.start()
            try:
                barrier.wait(180)
            except Exception:
                pass  # a worker failed to start: it reports why
            collected = _collect(workers, results)
    finally:
        if daemon is not None:
            daemon.stop()
    order = {uav: k for k, (uav, _) in enumerate(uavs)}
    reported = {r["uav"] for r in collected}
    for (uav, camera), spec in zip(uavs, session.trackers):
        if uav not in reported:
            collected.append({"tracker": spec, "uav": uav, "camera": camera, "lost": True,
                              "error": "its process ended without a result (a script run under the spawn start "
                                       "method needs an if __name__ == '__main__' guard)"})
    collected.sort(key=lambda r: order[r["uav"]])
    summary = {"session": asdict(session), "results": collected, "log": log_path}
    with open(os.path.join(out_dir, "session.json"), "w") as f:
        strict_json.dump(summary, f, indent=1)  # null, not NaN
    return summary
