"""A study as numbered tasks, so any scheduler can run it (docs/scaling.md).

    DIR/experiment.json        the checked experiment
    DIR/tasks.json             {"tasks": [...]}: index, kind (online | sequence | score), phase, name, what to do
    DIR/failed/<index>.json    why a task's last try failed (removed when it succeeds)
    DIR/logs/                  scheduler output (Slurm)

A task's result is the study's own file, written last by renaming, so one
that exists is complete: online, DIR/runs/<name>/session.json; sequence,
DIR/sequences/<name>/sequence.json marked complete; score,
DIR/results/<tracker>/<seq>.txt. A task whose result exists is skipped.
Phase 1 tasks (scores of generated sequences) start after phase 0's.
"""

import json
import os
import socket
import sys
import time

from . import experiment as ex
from . import experiment_offline as off

PLAN = "tasks.json"
INDEX_VARIABLES = ("SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "SGE_TASK_ID", "PBS_ARRAY_INDEX")


class TaskError(Exception):
    """A plan or task that cannot be used; the message says why."""


def write_atomic(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = "%s.%d.tmp" % (path, os.getpid())
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1)
    os.replace(tmp, path)


def make_tasks(exp, out_dir):
    if exp["kind"] == "online":
        return [{"kind": "online", "phase": 0, "name": run["name"], "run": run} for run in ex.online_runs(exp)]
    specs = off.generation_specs(exp)
    tasks = [{"kind": "sequence", "phase": 0, "name": s.name, "spec": {
        "map_": s.map, "speed": s.speed, "frames": s.frames, "laps": s.laps, "conditions": s.conditions,
        "channels": s.channels, "seed": s.seed, "quality": s.quality, "traffic_cars": s.traffic_cars,
        "name": s.name}} for s in specs]
    root = off.sequences_root(exp, out_dir)
    seqs = [s.name for s in specs] if specs else off.list_sequences(root)
    if not seqs:
        raise TaskError("no sequences (folders with groundtruth_rect.txt) in %s" % root)
    tasks += [{"kind": "score", "phase": 1 if specs else 0, "name": "%s on %s" % (w[0], w[2]), "work": list(w)}
              for w in off.score_work(exp, root, out_dir, seqs)]
    return tasks


def plan(exp, out_dir):
    """Writes DIR/experiment.json and DIR/tasks.json; the task list. A DIR
    planned before for a different experiment is refused."""
    out_dir = os.path.abspath(out_dir)
    tasks = make_tasks(exp, out_dir)
    for i, t in enumerate(tasks):
        t["index"] = i
    old = read_json(os.path.join(out_dir, PLAN))
    if old is not None and old.get("experiment") != json.loads(json.dumps(exp)):
        raise TaskError("%s holds another experiment (%s); use a new --out" % (out_dir, old["experiment"]["name"]))
    write_atomic(os.path.join(out_dir, "experiment.json"), exp)
    write_atomic(os.path.join(out_dir, PLAN), {"experiment": exp, "out": out_dir, "tasks": tasks})
    return tasks


read_json = ex._read_session  # a JSON file's content, or None when it is missing or cut short


def plan_commands(path, out_dir):
    """A task per line of `path` (a shell-free command line; # comments and
    blank lines skipped), run in the current folder: how the driving splits
    (driving generate per map, driving evaluate per model x map) and any
    other per-item command become tasks. Done: exit status 0."""
    import shlex
    try:
        with open(path) as f:
            lines = [line.strip() for line in f if line.strip() and not line.lstrip().startswith("#")]
    except OSError as e:
        raise TaskError("%s: %s" % (path, e))
    if not lines:
        raise TaskError("%s: no commands (one per line)" % path)
    try:
        tasks = [{"kind": "command", "phase": 0, "name": line, "argv": shlex.split(line), "cwd": os.getcwd()}
                 for line in lines]
    except ValueError as e:
        raise TaskError("%s: %s" % (path, e))
    exp = {"kind": "commands", "name": os.path.splitext(os.path.basename(path))[0], "commands": lines}
    for i, t in enumerate(tasks):
        t["index"] = i
    out_dir = os.path.abspath(out_dir)
    old = read_json(os.path.join(out_dir, PLAN))
    if old is not None and old.get("experiment") != exp:
        raise TaskError("%s holds another plan (%s); use a new --out" % (out_dir, old["experiment"]["name"]))
    write_atomic(os.path.join(out_dir, PLAN), {"experiment": exp, "out": out_dir, "tasks": tasks})
    return tasks


def load_plan(out_dir):
    data = read_json(os.path.join(out_dir, PLAN))
    if data is None:
        raise TaskError("%s has no readable %s: run `python3 -m sim4cv.experiment plan FILE.yaml --out %s` first"
                        % (out_dir, PLAN, out_dir))
    return data["experiment"], data["tasks"]


def index_from_environment():
    for name in INDEX_VARIABLES:
        value = os.environ.get(name, "")
        if value.strip().isdigit():
            return int(value)
    raise TaskError("no --index and none of %s is set" % ", ".join(INDEX_VARIABLES))


def is_done(out_dir, task):
    if task["kind"] == "online":
        return ex._read_session(os.path.join(out_dir, "runs", task["name"], "session.json")) is not None
    if task["kind"] == "command":
        return os.path.exists(os.path.join(out_dir, "done", "%06d.json" % task["index"]))
    if task["kind"] == "sequence":
        from .sequences import Spec, is_complete
        return is_complete(os.path.join(out_dir, "sequences", task["name"]), Spec(**task["spec"]))
    return os.path.exists(task["work"][4])


def failure_path(out_dir, index):
    return os.path.join(out_dir, "failed", "%06d.json" % index)


def _execute(out_dir, task, daemon):
    """Runs one task; its error text ('' when it succeeded)."""
    say = lambda text: print("sim4cv.experiment: %s" % text, file=sys.stderr, flush=True)  # noqa: E731
    if task["kind"] == "online":
        _, summary, _ = ex._run_online(task["run"], out_dir, daemon)
        return "" if is_done(out_dir, task) else summary["results"][0].get("error", "run failed")
    if task["kind"] == "command":
        return _run_command(out_dir, task)
    if task["kind"] == "sequence":
        from . import sequences as sq
        sq.generate([sq.Spec(**task["spec"])], os.path.join(out_dir, "sequences"), log=say)
        return ""
    *_, error, _, _ = off.score_one(tuple(task["work"]))
    return error


def _run_command(out_dir, task):
    import subprocess
    log = os.path.join(out_dir, "logs", "command_%06d.log" % task["index"])
    os.makedirs(os.path.dirname(log), exist_ok=True)
    t0 = time.monotonic()
    with open(log, "w") as f:
        try:
            rc = subprocess.run(task["argv"], cwd=task["cwd"], stdin=subprocess.DEVNULL, stdout=f,
                                stderr=subprocess.STDOUT).returncode
        except OSError as e:
            return "%s: %s" % (task["argv"][0], e)
    if rc != 0:
        with open(log, errors="replace") as f:
            last = [line.strip() for line in f if line.strip()][-1:] or [""]
        return "exit status %d (%s): %s" % (rc, log, last[0])
    write_atomic(os.path.join(out_dir, "done", "%06d.json" % task["index"]),
                 {"index": task["index"], "command": task["name"], "wall_s": time.monotonic() - t0,
                  "host": socket.gethostname()})
    return ""


def run_one(out_dir, index, daemon=None):
    """Runs task `index` unless its result exists: (skipped, error text)."""
    out_dir = os.path.abspath(out_dir)
    _, tasks = load_plan(out_dir)
    if not 0 <= index < len(tasks):
        raise TaskError("task index %d outside 0-%d (%s)" % (index, len(tasks) - 1, os.path.join(out_dir, PLAN)))
    task = tasks[index]
    if is_done(out_dir, task):
        return True, ""
    t0 = time.monotonic()
    try:
        error = _execute(out_dir, task, daemon)
    except Exception as e:  # recorded for status/gather; the scheduler sees a non-zero exit
        error = "%s: %s" % (type(e).__name__, e)
    if error:
        write_atomic(failure_path(out_dir, index), {"index": index, "name": task["name"], "error": error,
                                                    "host": socket.gethostname(), "wall_s": time.monotonic() - t0,
                                                    "time": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
    elif os.path.exists(failure_path(out_dir, index)):
        os.remove(failure_path(out_dir, index))
    return False, error


def status(out_dir):
    """{"done": [index], "failed": {index: reason}, "missing": [index], "tasks": [...]}"""
    _, tasks = load_plan(out_dir)
    done, failed, missing = [], {}, []
    for t in tasks:
        if is_done(out_dir, t):
            done.append(t["index"])
            continue
        failure = read_json(failure_path(out_dir, t["index"]))
        if failure is not None:
            failed[t["index"]] = failure["error"]
        else:
            missing.append(t["index"])
    return {"done": done, "failed": failed, "missing": missing, "tasks": tasks}


class TaskEnvironment:
    """What one task process sets up so that many run on a node without
    colliding: a marker SIM4CV_TASK=<job>-<index>-<pid> inherited by the
    daemon and tracker processes, a TMPDIR of its own (removed at the end),
    and LP_NUM_THREADS (llvmpipe's render threads) from the cores it was
    given (--cpus, else SLURM_CPUS_PER_TASK), unless already set.
    SIM4CV_TASK_DIR names the study's folder (several studies share a node)."""

    def __init__(self, index, cpus=None, out_dir=""):
        import tempfile
        job = os.environ.get("SLURM_ARRAY_JOB_ID") or os.environ.get("SLURM_JOB_ID") or "local"
        self.tag = "%s-%d-%d" % (job, index, os.getpid())
        cpus = cpus or os.environ.get("SLURM_CPUS_PER_TASK", "")
        if str(cpus).isdigit() and int(cpus) > 0:
            os.environ.setdefault("LP_NUM_THREADS", str(cpus))
        _remove_stale_folders(tempfile.gettempdir())
        self.tmp = tempfile.mkdtemp(prefix="sim4cv-task-%s-" % self.tag)
        os.environ.update(SIM4CV_TASK=self.tag, SIM4CV_TASK_DIR=os.path.abspath(out_dir), TMPDIR=self.tmp)
        # removes the folder when this process dies, kill -9 included (it gets SIGTERM then)
        import subprocess
        from .daemon import die_with_parent
        self.cleaner = subprocess.Popen([sys.executable, "-c", _CLEANER, self.tmp], stdin=subprocess.DEVNULL,
                                        preexec_fn=lambda: die_with_parent(15))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        import shutil
        self.cleaner.terminate()
        self.cleaner.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)  # also when the cleaner was killed before its handler was set


def _remove_stale_folders(parent):
    """Removes sim4cv-task-<job>-<index>-<pid>-* folders whose process is gone
    (a task killed with its whole process group, e.g. by Slurm, leaves its
    folder: the next task on the node removes it)."""
    import glob
    import shutil
    for path in glob.glob(os.path.join(parent, "sim4cv-task-*-*-*-*")):
        pid = os.path.basename(path).split("-")[-2]
        if pid.isdigit() and not os.path.exists("/proc/%s" % pid):
            shutil.rmtree(path, ignore_errors=True)


_CLEANER = """import shutil, signal, sys
signal.signal(signal.SIGTERM, lambda *a: (shutil.rmtree(sys.argv[1], ignore_errors=True), sys.exit(0)))
signal.pause()"""
