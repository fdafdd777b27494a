"""Who runs the tasks of a planned study (sim4cv.tasks): this machine
(local), a Slurm job array (slurm) or a Dask cluster (dask). Each task is its
own `python3 -m sim4cv.experiment run-one DIR --index I` process, so a
crashing task, a tracker process or a daemon never takes a worker with it
(docs/scaling.md)."""

import concurrent.futures
import os
import shlex
import subprocess
import sys
import time
import uuid

from . import tasks as tk
from .daemon import REPO_ROOT, daemon_path, die_with_parent

PYTHON_DIR = os.path.join(REPO_ROOT, "clients", "python")


def child_environment():
    """os.environ with this sim4cv first on PYTHONPATH and SIM4CVD absolute."""
    env = dict(os.environ, SIM4CVD=daemon_path())
    env["PYTHONPATH"] = os.pathsep.join([PYTHON_DIR] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def run_one_argv(out_dir, index=None, daemon=None, cpus=None):
    argv = [sys.executable, "-m", "sim4cv.experiment", "run-one", os.path.abspath(out_dir)]
    argv += ["--index", str(index)] if index is not None else []
    argv += ["--daemon", daemon] if daemon else []
    argv += ["--cpus", str(cpus)] if cpus else []
    return argv


def pending_by_phase(out_dir, only_unfinished=True):
    """{phase: [index]} of the tasks still to run (all tasks if not only_unfinished)."""
    st = tk.status(out_dir)
    todo = set(st["missing"]) | set(st["failed"]) if only_unfinished else {t["index"] for t in st["tasks"]}
    phases = {}
    for t in st["tasks"]:
        if t["index"] in todo:
            phases.setdefault(t["phase"], []).append(t["index"])
    return dict(sorted(phases.items()))


def run_task_process(argv, env):
    """Runs a run-one process in a session of its own: (exit status, its output).
    Whatever it leaves in that session when it ends (the tracker processes of a
    task killed with kill -9, which would otherwise hold its output pipe open
    for ever) is killed."""
    import tempfile
    with tempfile.TemporaryFile(mode="w+") as log:
        proc = subprocess.Popen(argv, env=env, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, preexec_fn=lambda: die_with_parent(15))  # Ctrl-C of `run`
        rc = proc.wait()
        _end_session(proc.pid)
        log.seek(0)
        return rc, log.read()


def _end_session(pgid, grace_s=10.0):
    """SIGTERM to what is left in the process group (Python's resource tracker
    ignores it and unlinks the task's semaphores once the others are gone),
    then SIGKILL to whatever is still there after grace_s."""
    import signal
    deadline = time.monotonic() + grace_s
    try:
        os.killpg(pgid, signal.SIGTERM)
        while time.monotonic() < deadline:
            time.sleep(0.1)
            os.killpg(pgid, 0)
        os.killpg(pgid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def _last_line(text):
    lines = [line for line in (text or "").splitlines() if line.strip()]
    return lines[-1] if lines else ""


# ----------------------------------------------------------------------------- local


def run_local(out_dir, jobs, daemon=None, progress_class=None):
    """Every task on this machine, `jobs` at a time, phase by phase; a task
    done before is skipped without starting a process."""
    from .experiment import Progress
    _, tasks = tk.load_plan(out_dir)
    env = child_environment()
    for phase in sorted({t["phase"] for t in tasks}):
        todo = [t for t in tasks if t["phase"] == phase]
        label = {"online": "runs", "sequence": "sequences to generate", "score": "(tracker, sequence) pairs",
                 "command": "commands"}
        progress = (progress_class or Progress)(len(todo), jobs, label[todo[0]["kind"]])

        def one(task):
            if tk.is_done(out_dir, task):
                return task, True, 0.0, ""
            t0 = time.monotonic()
            rc, output = run_task_process(run_one_argv(out_dir, task["index"], daemon), env)
            sys.stderr.write(output if rc else "")
            failure = tk.read_json(tk.failure_path(out_dir, task["index"])) if rc else None
            note = (failure or {}).get("error") or _last_line(output) if rc else ""
            return task, False, time.monotonic() - t0, note

        with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
            for task, skipped, seconds, note in pool.map(one, todo):
                if skipped and task["kind"] == "sequence":
                    progress.say("%s: complete, kept" % task["name"])
                    progress.done += 1
                    continue
                progress.step(task["name"], skipped, seconds, " (errors: %s)" % note if note else "")


# ----------------------------------------------------------------------------- slurm


def array_spec(indices):
    """'0-3,7,9-10' for [0, 1, 2, 3, 7, 9, 10]."""
    parts, indices = [], sorted(indices)
    start = prev = indices[0]
    for i in indices[1:] + [None]:
        if i is not None and i == prev + 1:
            prev = i
            continue
        parts.append("%d" % start if start == prev else "%d-%d" % (start, prev))
        if i is not None:
            start = prev = i
    return ",".join(parts)


def _sbatch(args, script):
    proc = subprocess.run(["sbatch", "--parsable"] + args + [script], capture_output=True, text=True)
    if proc.returncode != 0:
        raise tk.TaskError("sbatch %s failed: %s" % (" ".join(args), proc.stderr.strip() or proc.stdout.strip()))
    return proc.stdout.strip().split(";")[0]


def _script(path, lines, command):
    env = child_environment()
    body = ["#!/bin/bash"] + ["#SBATCH " + line for line in lines] + [
        "export PYTHONPATH=%s SIM4CVD=%s" % (shlex.quote(env["PYTHONPATH"]), shlex.quote(env["SIM4CVD"])),
        "cd %s" % shlex.quote(os.getcwd()), "exec " + " ".join(shlex.quote(a) for a in command)]
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("\n".join(body) + "\n")
    return path


def submit_slurm(out_dir, jobs, partition=None, time_limit=None, cpus_per_task=1, sbatch_lines=(), command_text="",
                 say=print):
    """One sbatch --array per phase of the unfinished tasks (at most `jobs`
    running at once) and a gather job after them; the job ids."""
    out_dir = os.path.abspath(out_dir)
    phases = pending_by_phase(out_dir)
    logs = os.path.join(out_dir, "logs")
    os.makedirs(logs, exist_ok=True)
    common = ["--cpus-per-task=%d" % cpus_per_task] + (["--partition=" + partition] if partition else []) + \
        (["--time=" + time_limit] if time_limit else [])
    name = "sim4cv-" + os.path.basename(out_dir)
    script = _script(os.path.join(out_dir, "slurm", "task.sh"), list(sbatch_lines),
                     run_one_argv(out_dir, cpus=cpus_per_task))
    ids, after = [], None
    for phase, indices in phases.items():
        array = "--array=%s%%%d" % (array_spec(indices), jobs)
        args = common + ["--job-name=%s-%d" % (name, phase), array, "--output=" + os.path.join(logs, "task_%a_job%A.out")]
        args += ["--dependency=afterany:" + after] if after else []
        after = _sbatch(args, script)
        ids.append(after)
        say("sbatch %s: job %s" % (array, after))
    gather = _script(os.path.join(out_dir, "slurm", "gather.sh"), list(sbatch_lines),
                     [sys.executable, "-m", "sim4cv.experiment", "gather", out_dir] +
                     (["--command", command_text] if command_text else []))
    args = common + ["--job-name=%s-gather" % name, "--output=" + os.path.join(logs, "gather_job%j.out")]
    args += ["--dependency=afterany:" + after] if after else []
    ids.append(_sbatch(args, gather))
    return ids


def wait_slurm(job_ids, poll_s=2.0, timeout_s=None):
    """Until squeue lists none of job_ids (or timeout_s passes: TaskError)."""
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    while True:
        proc = subprocess.run(["squeue", "-h", "-o", "%i", "-j", ",".join(job_ids)], capture_output=True, text=True)
        if proc.returncode == 0 and not proc.stdout.strip():
            return
        if deadline is not None and time.monotonic() > deadline:
            raise tk.TaskError("Slurm jobs %s still queued after %.0f s" % (",".join(job_ids), timeout_s))
        time.sleep(poll_s)


# ----------------------------------------------------------------------------- dask


def _dask_task(argv, env):
    """On a Dask worker: one run-one process (workers are daemonic and may not
    start the tracker processes themselves); raises on failure so Dask retries."""
    rc, output = run_task_process(argv, env)
    if rc != 0:
        raise RuntimeError("%s exited with %d: %s" % (" ".join(argv[3:]), rc, _last_line(output)))
    return rc


def run_dask(out_dir, jobs, address=None, retries=2, say=print):
    """The unfinished tasks on a Dask cluster (`address`, or a LocalCluster of
    `jobs` single-threaded workers), phase by phase; the errors of the tasks
    that failed every try."""
    from distributed import Client, LocalCluster, as_completed
    env = child_environment()
    os.environ["PYTHONPATH"] = env["PYTHONPATH"]  # LocalCluster workers import sim4cv.executors
    cluster = None if address else LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                                dashboard_address=None)
    client = Client(address or cluster)
    errors = {}
    try:
        token = uuid.uuid4().hex[:8]
        for phase, indices in pending_by_phase(out_dir).items():
            futures = {client.submit(_dask_task, run_one_argv(out_dir, i), env, key="sim4cv-%s-task-%d" % (token, i),
                                     retries=retries, pure=False): i for i in indices}
            for fut in as_completed(futures):
                i = futures[fut]
                try:
                    fut.result()
                    say("task %d done" % i)
                except Exception as e:  # failed every try: recorded by run-one in DIR/failed
                    errors[i] = str(e)
                    say("task %d failed: %s" % (i, e))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return errors
