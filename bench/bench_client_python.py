#!/usr/bin/python3
"""Python client benchmark: lockstep RGB frames over one transport.

    /usr/bin/python3 bench/bench_client_python.py --address shm:///x --frames 300

Subscribes ["rgb"] in lockstep to the daemon's default camera (over shared
memory: the ring's camera), steps and receives N frames, and prints one JSON
line: {"language": "python", "transport": ..., "fps": ..., "latency_median_us":
..., "latency_p90_us": ..., "frames": N}. Latency is render end to frame in
hand (Frame.render_end_mono_ns vs time.monotonic_ns(), both CLOCK_MONOTONIC),
with the RGB plane touched (its view taken). It does not start the daemon.

    /usr/bin/python3 bench/bench_client_python.py --address ADDR --age --frames 100

A reader asking for the newest frame every --period-ms (request_frame, of a
realtime daemon): prints the frames' age in hand (median, p90, max, in ms).
"""

import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "clients", "python"))

import sim4cv  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--address", required=True, help="tcp://HOST:PORT, udp://HOST:PORT or shm://NAME")
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--warmup", type=int, default=10)
    p.add_argument("--age", action="store_true", help="measure frame age of a slow reader instead")
    p.add_argument("--period-ms", type=int, default=100)
    args = p.parse_args()
    with sim4cv.connect(args.address, name="bench-python") as client:
        if client.transport == "shm":
            camera = client.ring_geometry.camera_name
        else:
            camera = client.welcome.cameras[0].name
        if args.age:
            return measure_age(client, camera, args)
        client.subscribe(camera, ["rgb"], "lockstep")
        for _ in range(args.warmup):
            client.step_and_receive()
        latencies = []
        start = time.monotonic()
        for _ in range(args.frames):
            frame = client.step_and_receive()
            frame.image("rgb")
            latencies.append((time.monotonic_ns() - frame.render_end_mono_ns) / 1000.0)
        elapsed = time.monotonic() - start
    latencies.sort()
    print(json.dumps({
        "language": "python",
        "transport": client.transport,
        "fps": round(args.frames / elapsed, 1),
        "latency_median_us": round(statistics.median(latencies), 1),
        "latency_p90_us": round(latencies[int(0.9 * (len(latencies) - 1))], 1),
        "frames": args.frames,
    }))


def measure_age(client, camera, args):
    client.subscribe(camera, ["rgb"], "on_request")
    ages = []
    for _ in range(args.frames):
        time.sleep(args.period_ms / 1000.0)
        frame = client.request_frame()
        frame.image("rgb")
        ages.append((time.monotonic_ns() - frame.render_end_mono_ns) / 1e6)
    ages.sort()
    print(json.dumps({
        "language": "python",
        "transport": client.transport,
        "period_ms": args.period_ms,
        "age_median_ms": round(statistics.median(ages), 1),
        "age_p90_ms": round(ages[int(0.9 * (len(ages) - 1))], 1),
        "age_max_ms": round(ages[-1], 1),
        "frames": args.frames,
    }))


if __name__ == "__main__":
    main()
