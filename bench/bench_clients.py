#!/usr/bin/python3
"""The client benchmark: every language's client over every transport, in one run.

    /usr/bin/python3 bench/bench_clients.py [--frames 300] [--age-reads 100]

1. Throughput and latency: one lockstep daemon (--shm-channels rgb); the C++
   (build/bench/sim4cv_bench_client_cpp), Python (bench/bench_client_python.py)
   and Octave (bench/bench_client_octave.m over the MEX client) clients each
   receive 320x180 RGB frames over TCP, UDP and shared memory in turn: frames
   per second and latency from render end to frame in hand.
2. Frame age: one realtime daemon at 30 Hz; each client asks for the newest
   frame every 100 ms (10 Hz); the frame's age in hand.
Prints two Markdown tables (docs/benchmarks.md, "Clients") with each
language's latency as a multiple of C++'s. Needs the build (build/).
"""

import argparse
import json
import os
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
DAEMON = os.path.join(ROOT, "build", "server", "daemon", "sim4cvd")
MEX_DIR = os.path.join(ROOT, "build", "clients", "matlab")


def start_daemon(args):
    name = "/sim4cv-bench-clients-%d-%d" % (os.getpid(), time.monotonic_ns() % 100000)
    proc = subprocess.Popen([DAEMON, "--tcp-port", "0", "--udp-port", "0", "--shm-name", name, "--shm-channels", "rgb",
                             "--log-level", "warning"] + args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)
    fields = dict(f.split("=", 1) for f in proc.stdout.readline().split()[2:])
    addresses = {"tcp": "tcp://127.0.0.1:" + fields["tcp"], "udp": "udp://127.0.0.1:" + fields["udp"],
                 "shm": "shm://" + fields["shm"]}
    return proc, addresses


def commands(address, frames, age):
    extra = ["--age", "--frames", str(frames)] if age else ["--frames", str(frames)]
    octave_call = "bench_client_octave('%s', %d, %s)" % (address, frames, "true" if age else "false")
    return {
        "c++": [os.path.join(ROOT, "build", "bench", "sim4cv_bench_client_cpp"), "--address", address] + extra,
        "python": ["/usr/bin/python3", os.path.join(ROOT, "bench", "bench_client_python.py"), "--address",
                   address] + extra,
        "octave": ["octave", "--no-gui", "--no-window-system", "--quiet", "--eval",
                   "addpath('%s', '%s', '%s'); %s" % (MEX_DIR, os.path.join(ROOT, "clients", "matlab"),
                                                        os.path.join(ROOT, "bench"), octave_call)],
    }


def run(command):
    try:
        out = subprocess.run(command, capture_output=True, text=True, timeout=600)
    except FileNotFoundError as e:
        return {"error": str(e)}
    for line in reversed(out.stdout.splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    return {"error": (out.stderr or out.stdout).strip().splitlines()[-1:] or ["no output"]}


def measure(daemon_args, frames, age):
    proc, addresses = start_daemon(daemon_args)
    results = {}
    try:
        for transport, address in addresses.items():
            for language, command in commands(address, frames, age).items():
                results[(language, transport)] = run(command)
                print("  %-6s %-3s %s" % (language, transport, results[(language, transport)]), file=sys.stderr)
    finally:
        proc.terminate()
        proc.wait(timeout=20)
    return results


def table(results, columns, ratio_of):
    rows = ["| client | transport | " + " | ".join(title for title, _ in columns) + " | vs C++ |",
            "|---" * (len(columns) + 3) + "|"]
    for language in ("c++", "python", "octave"):
        for transport in ("tcp", "udp", "shm"):
            r = results[(language, transport)]
            if "error" in r:
                rows.append("| %s | %s | %s |" % (language, transport, "not measured: %s" % r["error"]))
                continue
            base = results[("c++", transport)].get(ratio_of)
            ratio = "%.2fx" % (r[ratio_of] / base) if base else "-"
            rows.append("| %s | %s | %s | %s |" % (language, transport, " | ".join(str(r[key]) for _, key in columns),
                                                   ratio))
    return "\n".join(rows)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--age-reads", type=int, default=100)
    args = p.parse_args()
    started = time.monotonic()
    speed = measure(["--mode", "lockstep"], args.frames, age=False)
    ages = measure(["--mode", "realtime", "--frame-hz", "30"], args.age_reads, age=True)
    print("Lockstep 320x180 RGB, %d frames per client and transport:\n" % args.frames)
    print(table(speed, [("frames/s", "fps"), ("latency median (µs)", "latency_median_us"),
                        ("p90 (µs)", "latency_p90_us")], "latency_median_us"))
    print("\nFrame age of a reader asking every 100 ms (10 Hz) of a 30 Hz realtime stream, %d reads:\n"
          % args.age_reads)
    print(table(ages, [("age median (ms)", "age_median_ms"), ("p90 (ms)", "age_p90_ms"), ("max (ms)", "age_max_ms")],
                "age_median_ms"))
    print("\n(%.0f s)" % (time.monotonic() - started))


if __name__ == "__main__":
    main()
