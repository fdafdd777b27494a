"""The driving case study's command line (docs/driving.md):

    python3 -m sim4cv.driving generate --maps train --out DIR ...   (sim4cv.driving_dataset)
    python3 -m sim4cv.driving train --train DIR --val DIR --out OUT  (sim4cv.driving_train)
    python3 -m sim4cv.driving evaluate --model OUT/model.onnx --maps test --out DIR
    python3 -m sim4cv.driving evaluate --policy reference --maps test --out DIR
    python3 -m sim4cv.driving drive --model OUT/model.pt --frames shm://NAME --controls udp://H:P
                                                                     (sim4cv.driving_client)
    python3 -m sim4cv.driving human --map MAP --out DIR   (keyboard driving, scored: sim4cv.driving_human)
    python3 -m sim4cv.driving relabel --dataset DIR   (goals at junctions: sim4cv.driving_relabel)
    python3 -m sim4cv.driving compare --out DIR   (no / fixed / random views: sim4cv.driving_compare)
    python3 -m sim4cv.driving dagger --model M --maps train --out DIR   (the states M drives into: sim4cv.driving_dagger)
    python3 -m sim4cv.driving average --models A.pt B.pt ... --out DIR   (weight averaging: sim4cv.driving_average)
    python3 -m sim4cv.driving probe --model M --dataset DIR   (predictions beside labels: sim4cv.driving_probe)
    python3 -m sim4cv.driving head --init M.pt --train DIR --val DIR --out OUT   (FC layers only: driving_head)
"""

import argparse
import importlib
import sys
from typing import List, Optional

from . import driving_card as dcard
from . import driving_control as dc
from . import driving_eval as de


def evaluate_main(argv: List[str]) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving evaluate",
                                description="closed-loop evaluation of a driving policy (driving.json)")
    p.add_argument("--policy", choices=("network", "reference"), default="network")
    p.add_argument("--model", help="model.pt or model.onnx (policy network)")
    p.add_argument("--maps", nargs="+", default=["test"], help="train, val, test and/or map files")
    p.add_argument("--surroundings", default="desert,urban")
    p.add_argument("--out", required=True)
    p.add_argument("--speed", type=float, help="m/s, the controller's cap (default: the model card's, else 8)")
    p.add_argument("--conditions", default="",
                   help="weather/time-of-day preset (default clear_noon); several, comma-separated: one evaluation "
                        "each into OUT/PRESET/ and a comparison in OUT/conditions.md")
    p.add_argument("--lane", choices=("right", "left"), default="right",
                   help="left: mirror image, goal and h (the lane-change trick); a lap starts on the left lane and is "
                        "scored against its centre")
    p.add_argument("--frame-hz", type=float, help="the daemon's frame rate (default: the model card's, else 30)")
    p.add_argument("--obstacles", type=int, default=0,
                   help="cars parked in the lane per route, placed as the dataset places them (with --seed)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--transport", choices=de.TRANSPORTS, default="tcp",
                   help="the one connection to each daemon: tcp, or udp (frames, Steps and Controls on one UDP "
                        "socket, lockstep: the same laps as over TCP)")
    dc.add_arguments(p)
    a = p.parse_args(argv)
    if a.policy == "network" and not a.model:
        p.error("--policy network needs --model FILE")
    if a.policy == "network" and a.lane == "left" and a.obstacles:
        p.error("--lane left drives the left lane, where --obstacles are passed: use one of them")
    try:
        if a.policy == "reference":
            policy, card = de.ReferencePolicy(), None
        else:
            policy = de.NetworkPolicy(a.model, lane=a.lane)
            card = dcard.for_model(a.model, (policy.height, policy.width, policy.use_goal))
        settings_from = dcard.apply(a, card)
        controller = dc.from_arguments(p, a)
        print(dcard.describe(a, settings_from), flush=True)
        surroundings = [s for s in a.surroundings.split(",") if s]
        if "," in a.conditions:
            de.evaluate_conditions(policy, a.maps, surroundings, a.out, [c for c in a.conditions.split(",") if c],
                                   a.speed, a.frame_hz, obstacles=a.obstacles, seed=a.seed,
                                   controller=controller, settings_from=settings_from, transport=a.transport)
        else:
            de.evaluate(policy, a.maps, surroundings, a.out, a.speed, a.conditions, a.frame_hz,
                        obstacles=a.obstacles, seed=a.seed, controller=controller, settings_from=settings_from,
                        transport=a.transport)
    except (de.EvalError, RuntimeError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


def drive_main(argv: List[str]) -> int:
    from . import driving_client as dcl
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving drive",
                                description="drive a car with a policy: frames over shm/TCP, controls over UDP")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--model", help="model.pt (torch) or model.onnx (OpenCV DNN)")
    source.add_argument("--reference", metavar="MAP", help="the reference policy on this map file's route")
    p.add_argument("--frames", required=True, help="shm://NAME or tcp://HOST:PORT (the camera's frames)")
    p.add_argument("--controls", help="udp://HOST:PORT (default: the frames connection)")
    p.add_argument("--car", default="car", help="the car's entity name (default car)")
    p.add_argument("--camera", default="car_front")
    p.add_argument("--speed", type=float, help="m/s, the controller's cap (default: the model card's, else 8)")
    p.add_argument("--lockstep", action="store_true", help="step the world; controls over the frames connection")
    p.add_argument("--lane", choices=("right", "left"), default="right")
    p.add_argument("--switch-every", type=float, default=0.0, help="change lanes every S simulated seconds")
    p.add_argument("--seconds", type=float, default=0.0, help="stop after S simulated seconds (0: never)")
    p.add_argument("--frames-count", type=int, default=0, help="stop after N frames (0: never)")
    dc.add_arguments(p)
    a = p.parse_args(argv)
    try:
        policy = dcl.ReferenceDriver(a.reference) if a.reference else de.NetworkPolicy(a.model)
        card = None if a.reference else dcard.for_model(a.model, (policy.height, policy.width, policy.use_goal))
        settings_from = dcard.apply(a, card)
        controller = dc.from_arguments(p, a)
        print(dcard.describe(a, settings_from), flush=True)
        lane = dcl.Lane(a.lane, a.switch_every)
        if not a.switch_every:  # type left / right on stdin to change lanes
            lane.listen()
        result = dcl.drive(a.frames, a.controls, policy, a.car, a.camera, a.speed, a.lockstep, a.seconds,
                           a.frames_count, lane, log=lambda m: print(m, flush=True), controller=controller)
    except (de.EvalError, RuntimeError, OSError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    print(result, flush=True)
    return 0


def human_main(argv: List[str]) -> int:
    from . import driving_client as dcl
    from . import driving_human as dh
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving human",
                                description="drive with the keyboard in an OpenCV window; scored like the network")
    p.add_argument("--map", required=True, help="the map file (its route is the ideal path)")
    p.add_argument("--out", required=True, help="folder for driving.json and the trajectory")
    p.add_argument("--address", help="a running daemon's frames address (tcp:// or shm://); default: start one")
    p.add_argument("--controls", help="udp://HOST:PORT of that daemon (default: its frames connection)")
    p.add_argument("--camera", default="car_front", help="car_front (first person) or car_chase")
    p.add_argument("--name", default="human", help="the driver's name in driving.json")
    p.add_argument("--seconds", type=float, default=0.0, help="stop after S seconds (default: one lap)")
    a = p.parse_args(argv)
    from .daemon import OwnDaemon
    driver = dh.KeyboardDriver(window="sim4cv: drive with the arrow keys, q to stop")
    scorer = dh.Scorer(a.map)
    scorer.driver = driver
    try:
        if a.address:
            dcl.drive(a.address, a.controls, driver, camera=a.camera, seconds=a.seconds, recorder=scorer)
        else:
            flags = ["--map", a.map, "--traffic-cars", "0", "--traffic-parked", "0", "--traffic-pedestrians", "0"]
            with OwnDaemon(flags, mode="realtime") as d:
                dcl.drive(d.address, "udp://127.0.0.1:%s" % d.fields["udp"], driver, camera=a.camera,
                          seconds=a.seconds, recorder=scorer)
    except (de.EvalError, RuntimeError, OSError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    o = scorer.report(a.out, a.name)["overall"]
    print("%s: mean deviation %s cm, within 25 cm %s, lane departures %d, %.0f m"
          % (a.name, o["mean_deviation_cm"], o["within_25cm"], o["lane_departures"], o["distance_m"]))
    return 0


def generate_main(argv: List[str]) -> int:
    from . import driving_dataset  # its command line holds generate among others
    return driving_dataset.main(["generate"] + argv)


# the commands that are a module's main(argv), one line each
MODULES = {"train": "driving_train", "relabel": "driving_relabel", "dagger": "driving_dagger",
           "average": "driving_average", "probe": "driving_probe", "compare": "driving_compare",
           "head": "driving_head"}


def main(argv: Optional[List[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    local = {"evaluate": evaluate_main, "drive": drive_main, "human": human_main, "generate": generate_main}
    if argv in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    if not argv or argv[0] not in set(MODULES) | set(local):
        print(__doc__, file=sys.stderr)
        return 2
    command, rest = argv[0], argv[1:]
    if command in local:
        return local[command](rest)
    return importlib.import_module("." + MODULES[command], __package__).main(rest)


if __name__ == "__main__":
    sys.exit(main())
