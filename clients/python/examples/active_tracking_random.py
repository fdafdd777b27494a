#!/usr/bin/python3
"""Runs a random agent and the scripted expert in the active-tracking environment and prints their mean rewards.

Each agent flies the UAV for --frames env steps (resetting when an episode
ends), starting from reset(seed=--seed); the environment starts its own
sim4cvd unless --address names a running lockstep daemon.

    /usr/bin/python3 clients/python/examples/active_tracking_random.py --frames 300
    /usr/bin/python3 clients/python/examples/active_tracking_random.py --map hard_urban --car-speed 8
    /usr/bin/python3 clients/python/examples/active_tracking_random.py --address tcp://127.0.0.1:5000
"""

import numpy as np

from _common import parser

from sim4cv.active_tracking import ActiveTrackingEnv


def run(env, policy, steps, seed):
    """`steps` env steps with `policy(obs, info)`; returns (mean reward, episodes ended, steps run)."""
    rewards, ended = [], 0
    obs, info = env.reset(seed=seed)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        rewards.append(reward)
        if terminated or truncated:
            ended += 1
            obs, info = env.reset()
    return float(np.mean(rewards)), ended, len(rewards)


def main():
    p = parser(__doc__.splitlines()[0], default_frames=300)
    p.set_defaults(address=None)
    p.add_argument("--map", default=None, help="a tracking map, e.g. easy_desert (default: the default scene)")
    p.add_argument("--car-speed", type=float, default=None, help="the target car's speed, m/s")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--frame-skip", type=int, default=1)
    args = p.parse_args()
    with ActiveTrackingEnv(address=args.address, map=args.map, car_speed=args.car_speed, camera=args.camera,
                           frame_skip=args.frame_skip) as env:
        env.action_space.seed(args.seed)
        agents = [("random", lambda obs, info: env.action_space.sample()),
                  ("expert", lambda obs, info: env.expert_action(info))]
        for name, policy in agents:
            mean, ended, steps = run(env, policy, args.frames, args.seed)
            print("%s agent: mean reward %.3f over %d steps (%d episodes ended)" % (name, mean, steps, ended))


if __name__ == "__main__":
    main()
