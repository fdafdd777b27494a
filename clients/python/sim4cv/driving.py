"""The driving case study's command line (docs/driving.md):

    python3 -m sim4cv.driving generate --maps train --out DIR ...   (sim4cv.driving_dataset)
    python3 -m sim4cv.driving train --train DIR --val DIR --out OUT  (sim4cv.driving_train)
    python3 -m sim4cv.driving evaluate --model OUT/model.onnx --maps test --out DIR
    python3 -m sim4cv.driving evaluate --policy reference --maps test --out DIR
"""

import argparse
import sys
from typing import List, Optional

from . import driving_eval as de


def evaluate_main(argv: List[str]) -> int:
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.driving evaluate",
                                description="closed-loop evaluation of a driving policy (driving.json)")
    p.add_argument("--policy", choices=("network", "reference"), default="network")
    p.add_argument("--model", help="model.pt or model.onnx (policy network)")
    p.add_argument("--maps", nargs="+", default=["test"], help="train, val, test and/or map files")
    p.add_argument("--surroundings", default="desert,urban")
    p.add_argument("--out", required=True)
    p.add_argument("--speed", type=float, default=de.DEFAULT_SPEED, help="m/s, the controller's cap")
    p.add_argument("--conditions", default="", help="weather/time-of-day preset of the daemon (default clear_noon)")
    p.add_argument("--lane", choices=("right", "left"), default="right",
                   help="left: mirror image and h (the lane-change trick); scored against the right lane")
    p.add_argument("--frame-hz", type=float, default=30.0)
    a = p.parse_args(argv)
    try:
        if a.policy == "reference":
            policy = de.ReferencePolicy()
        else:
            if not a.model:
                p.error("--policy network needs --model FILE")
            policy = de.NetworkPolicy(a.model, lane=a.lane)
            policy.path = a.model
        de.evaluate(policy, a.maps, [s for s in a.surroundings.split(",") if s], a.out, a.speed, a.conditions,
                    a.frame_hz)
    except (de.EvalError, RuntimeError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    commands = {"generate": "sim4cv.driving_dataset", "train": "sim4cv.driving_train", "evaluate": None}
    if not argv or argv[0] not in commands:
        print(__doc__, file=sys.stderr)
        return 2
    command, rest = argv[0], argv[1:]
    if command == "evaluate":
        return evaluate_main(rest)
    if command == "generate":
        from . import driving_dataset
        return driving_dataset.main(["generate"] + rest)
    from . import driving_train
    return driving_train.main(rest)


if __name__ == "__main__":
    sys.exit(main())
