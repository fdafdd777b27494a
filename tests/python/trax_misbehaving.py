#!/usr/bin/python3
"""A TraX tracker that misbehaves on request, for tests/python/test_trax.py.

It says hello, then answers every initialize and frame with the state
"10,20,30,40" (frames: --region), until the request after the first N
answered ones, where it does what the option says:

    --crash-after N     writes "boom: simulated crash" to stderr and exits with code 3
    --signal-after N    kills itself with SIGSEGV
    --garbage-after N   prints a malformed TraX line: @@TRAX:state "12,34
    --hang-after N      stops reading its input and sleeps (N = -1: before its hello)
    --error-after N     sends @@TRAX:error "model exploded"
    --quit-after N      sends @@TRAX:quit with trax.reason=out of memory
    --exit-after N      exits with code 0 without a word

--flood-after N     answers with an endless stream of state lines
--stderr-bytes B    writes B bytes to stderr without a newline before its hello
--setsid-child      like --spawn-child, but the grandchild leaves the group with setsid()

--chatter prints lines that are not TraX messages on stdout and stderr
before every answer; --spawn-child starts a grandchild that sleeps (its pid
is in the hello as test.child_pid). Standard library only: starts fast.
"""

import argparse
import os
import resource
import signal
import subprocess
import sys
import time


def main():
    p = argparse.ArgumentParser()
    for name in ("crash", "signal", "garbage", "hang", "error", "quit", "exit"):
        p.add_argument("--%s-after" % name, type=int, default=None)
    p.add_argument("--version", default="3", help="trax.version to announce (any text)")
    p.add_argument("--image-formats", default="path;memory;")
    p.add_argument("--region-formats", default="rectangle;")
    p.add_argument("--channels", default="color;")
    p.add_argument("--region", default="10,20,30,40", help="the region answered to frames")
    p.add_argument("--chatter", action="store_true")
    p.add_argument("--spawn-child", action="store_true")
    p.add_argument("--setsid-child", action="store_true")
    p.add_argument("--flood-after", type=int, default=None)
    p.add_argument("--stderr-bytes", type=int, default=0)
    a = p.parse_args()
    out = sys.stdout

    def say(line):
        if a.chatter:
            out.write("tracker log: this line is not for the protocol\n")
            sys.stderr.write("tracker stderr: working\n")
        out.write(line + "\n")
        out.flush()

    if a.hang_after == -1:
        time.sleep(3600)
    child = ""
    if a.spawn_child or a.setsid_child:
        child = ' "test.child_pid=%d"' % subprocess.Popen(
            [sys.executable, "-c", "import time; time.sleep(300)"], start_new_session=a.setsid_child).pid
    chunk = b"x" * (1 << 20)
    for _ in range(a.stderr_bytes >> 20):
        os.write(2, chunk)
    say('@@TRAX:hello "trax.version=%s" "trax.name=misbehaving" "trax.region=%s" "trax.image=%s" '
        '"trax.channels=%s"%s' % (a.version, a.region_formats, a.image_formats, a.channels, child))
    answered = 0
    while True:
        if a.hang_after == answered:
            time.sleep(3600)
        line = sys.stdin.readline()
        if not line:
            return
        kind = line.split(" ", 1)[0].strip()
        if kind == "@@TRAX:quit":
            return
        if kind not in ("@@TRAX:initialize", "@@TRAX:frame"):
            continue
        if a.crash_after == answered:
            sys.stderr.write("boom: simulated crash\n")
            sys.stderr.flush()
            os._exit(3)
        if a.signal_after == answered:
            resource.setrlimit(resource.RLIMIT_CORE, (0, 0))    # no core file
            os.kill(os.getpid(), signal.SIGSEGV)
        if a.exit_after == answered:
            os._exit(0)
        if a.flood_after == answered:
            # 256 lines per write: the client sees far more than it may hold
            # at once, however slowly a busy machine runs this process.
            block = '@@TRAX:state "1,2,3,4"\n' * 256
            while True:
                out.write(block)
                out.flush()
        if a.garbage_after == answered:
            say('@@TRAX:state "12,34')
        elif a.error_after == answered:
            say('@@TRAX:error "model exploded"')
        elif a.quit_after == answered:
            say('@@TRAX:quit "trax.reason=out of memory"')
        else:
            say('@@TRAX:state "%s"' % ("10,20,30,40" if kind == "@@TRAX:initialize" else a.region))
        answered += 1


if __name__ == "__main__":
    main()
