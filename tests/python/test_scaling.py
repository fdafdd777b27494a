"""Studies as tasks on real schedulers (docs/scaling.md): a one-machine Slurm
cluster (tests/python/local_slurm.py), a Dask LocalCluster and dask-scheduler
+ dask-worker processes each run tests/python/scaling_sweep.yaml; one task is
killed and resubmitted; the gathered results equal the local executor's
(lockstep runs are deterministic: the per-frame CSVs are byte-identical but
for the tracker's measured update_ms). And a task killed with kill -9 leaves
no process and no shared-memory file behind. Needs build/server/daemon/sim4cvd."""

import csv
import json
import os
import signal
import subprocess
import sys
import time

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sim4cv.proctree import environments  # noqa: E402

SWEEP = os.path.join(REPO_ROOT, "tests", "python", "scaling_sweep.yaml")
ENV = dict(os.environ, PYTHONPATH=os.path.join(REPO_ROOT, "clients", "python"))
DETERMINISTIC = ("run", "tracker", "speed", "completion", "frames_processed", "frames_skipped",
                 "mean_center_error_px", "median_center_error_px", "mean_distance_m", "lost", "error",
                 "deviation_from_gt_m")


def cli(*args, env=None, timeout=240):
    return subprocess.run([sys.executable, "-m", "sim4cv.experiment"] + [str(a) for a in args], cwd=REPO_ROOT,
                          env=env or ENV, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("local") / "sweep"
    proc = cli("run", SWEEP, "--out", out, "--jobs", "2")
    assert proc.returncode == 0, proc.stderr
    return out


def frames(out):
    """{run/frames_k.csv: rows without the measured update_ms}"""
    tables = {}
    for run in sorted(os.listdir(out / "runs")):
        for name in sorted(os.listdir(out / "runs" / run)):
            if name.startswith("frames_"):
                with open(out / "runs" / run / name) as f:
                    tables[run + "/" + name] = [{k: v for k, v in row.items() if k != "update_ms"}
                                                for row in csv.DictReader(f)]
    return tables


def assert_same_results(out, reference):
    mine, theirs = frames(out), frames(reference)
    assert sorted(mine) == sorted(theirs)
    for name in theirs:
        diff = [(k, a, b) for k, (a, b) in enumerate(zip(mine[name], theirs[name])) if a != b][:3]
        assert len(mine[name]) == len(theirs[name]) and not diff, (name, len(mine[name]), len(theirs[name]), diff)
    assert len(frames(out)) == 4 and all(len(rows) > 100 for rows in frames(out).values())
    pick = lambda path: [{k: r[k] for k in DETERMINISTIC} for r in json.loads((path / "results.json").read_text())]
    assert pick(out) == pick(reference)
    assert "Tasks not done" not in (out / "report.md").read_text()


def marked_processes(marker, out_dir):
    """PIDs whose environment holds SIM4CV_TASK=<marker...> and SIM4CV_TASK_DIR=out_dir
    (other tests' studies may run beside)."""
    task, folder = ("SIM4CV_TASK=" + marker).encode(), ("SIM4CV_TASK_DIR=%s" % out_dir).encode()
    return [pid for pid, environment in environments()
            if folder in environment and any(entry.startswith(task) for entry in environment)]


def mapped_by_a_live_process(path):
    """Whether some process's memory maps the file at `path` (/proc/*/maps, by inode: glibc's
    sem_open maps a temporary file it then links to the semaphore's name)."""
    try:
        inode = str(os.stat(path).st_ino)
    except OSError:
        return True  # gone meanwhile: not left behind
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/maps" % pid) as f:
                if any(len(fields) >= 6 and fields[4] == inode and fields[5].startswith("/dev/shm/")
                       for fields in (line.split() for line in f)):
                    return True
        except OSError:
            continue
    return False


def comm(pid):
    try:
        with open("/proc/%d/comm" % pid) as f:
            return f.read().strip()
    except OSError:
        return ""


def wait_for(predicate, timeout=120, what="condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError("timed out waiting for " + what)


def task_mid_run(prefix, out_dir):
    """(marker, run-one pid) of a task whose marker starts with `prefix` once its daemon and
    tracker processes are up: killed then, it cannot have written its result."""
    daemon = wait_for(lambda: [p for p in marked_processes(prefix, out_dir) if comm(p) == "sim4cvd"],
                      what="a daemon marked " + prefix)
    marker = [line.split("=", 1)[1] for line in open("/proc/%d/environ" % daemon[0], "rb").read().decode().split("\0")
              if line.startswith("SIM4CV_TASK=")][0]
    # run-one, daemon, tracker
    wait_for(lambda: len(marked_processes(marker, out_dir)) >= 3, what="the tracker process of " + marker)
    return marker, int(marker.split("-")[-1])  # the run-one process: <job>-<index>-<pid>


def test_task_killed_with_kill9_leaves_nothing(tmp_path):
    """A task of the local executor killed with kill -9 mid-run (its daemon and
    tracker processes up) leaves no process, semaphore or temporary folder, and
    the executor goes on with the other tasks."""
    out = tmp_path / "killed"
    shm_before = set(os.listdir("/dev/shm"))
    run = subprocess.Popen([sys.executable, "-m", "sim4cv.experiment", "run", SWEEP, "--jobs", "1", "--out", str(out)],
                           cwd=REPO_ROOT, env=ENV, stderr=subprocess.PIPE, text=True)
    marker, task_pid = task_mid_run("local-1-", out)
    shm_during = set(os.listdir("/dev/shm")) - shm_before
    os.kill(task_pid, signal.SIGKILL)
    _, err = run.communicate(timeout=240)
    assert run.returncode == 1, err  # one task not done
    assert not marked_processes(marker, out)
    # A semaphore another live process (a test running beside this one) still maps is not the
    # killed task's; one nobody maps is a leftover.
    leftovers = [n for n in shm_during & set(os.listdir("/dev/shm"))
                 if (n.startswith("sem.mp") or marker in n) and not mapped_by_a_live_process("/dev/shm/" + n)]
    assert not leftovers, leftovers
    assert not [d for d in os.listdir("/tmp") if d.startswith("sim4cv-task-" + marker)]
    status = cli("status", out)
    assert status.returncode == 1 and "3 done, 0 failed, 1 missing" in status.stdout, status.stdout
    assert "missing 1 " in status.stdout, status.stdout


@pytest.mark.parametrize("cpus, slurm_cpus, threads", [("3", "", 3), ("", "1", 1)])
def test_task_llvmpipe_threads_follow_allocation(cpus, slurm_cpus, threads):
    """Mesa's llvmpipe starts LP_NUM_THREADS render threads (llvmpipe-N), set
    from run-one's --cpus or Slurm's SLURM_CPUS_PER_TASK."""
    code = ("import glob, os, sim4cv; from sim4cv.tasks import TaskEnvironment; from sim4cv.daemon import OwnDaemon\n"
            "with TaskEnvironment(0, %r or None), OwnDaemon(['--map', 'scenes/tracking/easy_urban.map']) as d:\n"
            "    sim4cv.connect(d.address).close()\n"
            "    names = [open(t + '/comm').read() for t in glob.glob('/proc/%%d/task/*' %% d.proc.pid)]\n"
            "    print(sum(n.startswith('llvmpipe-') for n in names))" % cpus)
    env = {k: v for k, v in ENV.items() if k not in ("LP_NUM_THREADS", "SLURM_CPUS_PER_TASK")}
    env.update({"SLURM_CPUS_PER_TASK": slurm_cpus} if slurm_cpus else {})
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO_ROOT, env=env, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == [str(threads)]


def test_slurm_sweep_kill_resubmit_gather(tmp_path, reference):
    from local_slurm import LocalSlurm
    out = tmp_path / "slurm"
    with LocalSlurm(cpus=2) as slurm:
        env = dict(ENV, SLURM_CONF=slurm.env["SLURM_CONF"], PATH=slurm.env["PATH"])
        proc = cli("run", SWEEP, "--executor", "slurm", "--jobs", "2", "--out", out, env=env)
        assert proc.returncode == 0 and "submitted Slurm jobs" in proc.stderr, proc.stderr
        array_job = proc.stderr.split("submitted Slurm jobs ")[1].split(",")[0]
        # kill task 0 mid-run: its daemon (marked <array job>-<index>-<pid>) is up
        wait_for(lambda: [p for p in marked_processes("%s-0-" % array_job, out) if comm(p) == "sim4cvd"],
                 what="task 0's daemon")
        subprocess.run(["scancel", "--signal=KILL", "%s_0" % array_job], env=env, check=True)
        wait_for(lambda: not subprocess.run(["squeue", "-h"], env=env, capture_output=True, text=True).stdout.strip(),
                 what="the array and the gather job")
        status = cli("status", out, env=env)
        assert status.returncode == 1 and "3 done, 0 failed, 1 missing" in status.stdout, status.stdout
        assert "missing 0 easy_urban_s6_lockstep" in status.stdout
        report = (out / "report.md").read_text()  # the gather job ran after the array
        assert "Tasks not done (1 of 4" in report and "- 0 easy_urban_s6" in report
        again = cli("resubmit", out, "--executor", "slurm", "--jobs", "2", "--wait", env=env)
        assert again.returncode == 0, again.stderr + again.stdout
        with open(out / "slurm" / "task.sh") as f:
            assert "run-one" in f.read()
        assert "--array=0%2" in again.stderr, again.stderr  # only the missing task
        # the killed task's temporary folder went with its process group; the next task on the node removed it
        assert not [d for d in os.listdir("/tmp") if d.startswith("sim4cv-task-%s-0-" % array_job)]
    assert cli("status", out).stdout.startswith("4 tasks: 4 done")
    assert_same_results(out, reference)


def test_dask_local_cluster_kill_resubmit(tmp_path, reference):
    out = tmp_path / "dask"
    run = subprocess.Popen([sys.executable, "-m", "sim4cv.experiment", "run", SWEEP, "--executor", "dask", "--jobs",
                            "2", "--retries", "0", "--out", str(out)], cwd=REPO_ROOT, env=ENV, stderr=subprocess.PIPE,
                           text=True)
    # the first task whose daemon and tracker are up (a fixed sleep raced a fast task's end)
    _, victim = task_mid_run("local-", out)
    os.kill(victim, signal.SIGKILL)
    _, err = run.communicate(timeout=240)
    assert run.returncode == 1 and "failed" in err, err  # no retries: one task is not done
    status = cli("status", out)
    assert "3 done" in status.stdout and "1 missing" in status.stdout, status.stdout + err
    again = cli("resubmit", out, "--executor", "dask", "--jobs", "2")
    assert again.returncode == 0 and again.stderr.count(" done") >= 1, again.stderr
    assert_same_results(out, reference)


def test_dask_scheduler_and_workers(tmp_path, reference):
    out = tmp_path / "dask_procs"
    port = __import__("local_slurm").free_port()
    procs = [subprocess.Popen(["dask-scheduler", "--host", "127.0.0.1", "--port", str(port), "--dashboard-address",
                               ":0"], env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(2):
            procs.append(subprocess.Popen(["dask-worker", "tcp://127.0.0.1:%d" % port, "--nthreads", "1",
                                           "--no-dashboard"], env=ENV, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL))
        proc = cli("run", SWEEP, "--executor", "dask", "--scheduler", "tcp://127.0.0.1:%d" % port, "--out", out)
        assert proc.returncode == 0, proc.stderr
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    assert_same_results(out, reference)


def test_task_index_from_scheduler_variables(tmp_path):
    out = tmp_path / "plan"
    planned = cli("plan", SWEEP, "--out", out)
    assert planned.returncode == 0 and "4 tasks in" in planned.stdout, planned.stderr
    bare = {k: v for k, v in ENV.items() if k not in ("SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "SGE_TASK_ID",
                                                      "PBS_ARRAY_INDEX")}
    proc = cli("run-one", out, env=bare)
    assert proc.returncode == 2 and "no --index and none of SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX" in proc.stderr
    for name in ("SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "SGE_TASK_ID", "PBS_ARRAY_INDEX"):
        proc = cli("run-one", out, env=dict(bare, **{name: "7"}))
        assert proc.returncode == 2 and "task index 7 outside 0-3" in proc.stderr, (name, proc.stderr)
    other = tmp_path / "other.yaml"
    other.write_text(open(SWEEP).read().replace("speeds: [6, 8]", "speeds: [6]"))
    proc = cli("plan", other, "--out", out)
    assert proc.returncode == 2 and "holds another experiment (scaling_sweep); use a new --out" in proc.stderr


def test_task_commands_plan_run_resubmit(tmp_path):
    """A file of commands (how the driving splits run per map) as tasks: the
    failing one is reported with its exit status and last line, and
    resubmit runs it alone once it can succeed."""
    flag = tmp_path / "ready"
    write = "/usr/bin/python3 -c \"import sys; open(sys.argv[1], 'w').write(sys.argv[2])\" %s %s"
    needs_flag = ("/usr/bin/python3 -c \"import os, sys; os.path.exists(sys.argv[1]) or sys.exit('no flag yet'); "
                  "open(sys.argv[2], 'w').write('c')\" %s %s" % (flag, tmp_path / "c.txt"))
    commands = tmp_path / "commands.txt"
    commands.write_text("# one line per task\n%s\n%s\n\n%s\n" % (write % (tmp_path / "a.txt", "a"), needs_flag,
                                                                write % (tmp_path / "b.txt", "b")))
    out = tmp_path / "tasks"
    assert cli("plan-commands", commands, "--out", out).stdout.startswith("3 tasks in")
    first = cli("resubmit", out, "--jobs", "2")
    assert first.returncode == 1, first.stderr
    status = cli("status", out)
    assert "3 tasks: 2 done, 1 failed, 0 missing" in status.stdout
    assert "failed 1 " in status.stdout and "exit status 1" in status.stdout and "no flag yet" in status.stdout
    assert "failed: exit status 1" in (out / "report.md").read_text()
    flag.write_text("")
    os.remove(tmp_path / "a.txt")  # done tasks are not run again
    again = cli("resubmit", out, "--jobs", "2")
    assert again.returncode == 0, again.stderr
    assert not (tmp_path / "a.txt").exists() and (tmp_path / "c.txt").read_text() == "c"
    assert "3 done" in (out / "report.md").read_text()
