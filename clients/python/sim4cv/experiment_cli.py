"""The command line of sim4cv.experiment (docs/tracking.md, "Experiments";
docs/scaling.md): run, plan, run-one, status, gather, resubmit and
plan-commands, each a thin layer over sim4cv.tasks, sim4cv.executors and
sim4cv.tasks_gather. Run as `python3 -m sim4cv.experiment` or `sim4cv experiment`."""

import argparse
import os
import signal
import sys
import time

from .experiment import ExperimentError, load


def _parser():
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.experiment",
                                description="Scripted online/offline tracking experiments (docs/tracking.md, "
                                            "'Experiments'), as numbered tasks for a cluster (docs/scaling.md).")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="plan, run (or resume) and gather an experiment file")
    pl = sub.add_parser("plan", help="write DIR/tasks.json: the numbered tasks of an experiment file")
    for q in (r, pl):
        q.add_argument("file", help="experiment YAML")
        q.add_argument("--out", required=True, help="output folder (created; reused to resume)")
    pc = sub.add_parser("plan-commands", help="write DIR/tasks.json: one task per line of a file of commands "
                                              "(e.g. driving generate per map, driving evaluate per model and map)")
    pc.add_argument("file", help="one command line per line; # comments")
    pc.add_argument("--out", required=True, help="the task folder")
    rs = sub.add_parser("resubmit", help="run the failed and missing tasks of a planned DIR again")
    rs.add_argument("out", help="the planned folder")
    for q in (r, rs):
        q.add_argument("--executor", choices=("local", "slurm", "dask"), default="local",
                       help="local: processes on this machine (default); slurm: a job array; dask: a Dask cluster")
        q.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 1) // 2),
                       help="tasks at once (local: processes, each with its own daemon; slurm: the array's %%J "
                            "limit; dask: LocalCluster workers); default cores // 2, at least 1")
        q.add_argument("--daemon", help="local: ADDRESS of a running sim4cvd to use (online, --jobs 1, one map/"
                                        "speed/fps/conditions that match the daemon's; no run logs)")
        q.add_argument("--partition", help="slurm: the partition")
        q.add_argument("--time", help="slurm: each task's time limit (sbatch --time)")
        q.add_argument("--cpus-per-task", type=int, default=1, help="slurm: cores per task (default 1; sets "
                                                                    "LP_NUM_THREADS)")
        q.add_argument("--sbatch-line", action="append", default=[], metavar="LINE",
                       help="slurm: an extra '#SBATCH LINE' in the job scripts (repeatable)")
        q.add_argument("--wait", action="store_true", help="slurm: wait until the gather job has run")
        q.add_argument("--scheduler", help="dask: the scheduler's ADDRESS (default: a LocalCluster of --jobs)")
        q.add_argument("--retries", type=int, default=2, help="dask: tries after a task's first failure")
    one = sub.add_parser("run-one", help="run one task of a planned DIR (skipped if its result exists)")
    one.add_argument("out", help="the planned folder")
    one.add_argument("--index", type=int, help="the task; default from SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, "
                                               "SGE_TASK_ID or PBS_ARRAY_INDEX")
    one.add_argument("--cpus", type=int, help="cores given to the task (LP_NUM_THREADS; default "
                                              "SLURM_CPUS_PER_TASK)")
    one.add_argument("--daemon", help="ADDRESS of a running sim4cvd (online tasks)")
    for name, text in (("status", "list done, failed (with the reason) and missing tasks"),
                       ("gather", "results.json, CSV, plots and report.md from the tasks done so far")):
        q = sub.add_parser(name, help=text)
        q.add_argument("out", help="the planned folder")
        q.add_argument("--command", dest="command_text", help=argparse.SUPPRESS)
    return p


def _check(exp, args):
    if args.jobs < 1:
        raise ExperimentError("--jobs must be at least 1")
    if args.daemon and (args.executor != "local" or exp["kind"] != "online" or args.jobs != 1 or
                        any(len(exp[k]) > 1 for k in ("maps", "speeds", "fps", "conditions"))):
        raise ExperimentError("--daemon needs the local executor, an online experiment, --jobs 1 and one map, speed, "
                              "fps and conditions (those the daemon was started with)")


def _execute(args, exp, command):
    from . import executors, tasks_gather
    t0 = time.monotonic()
    say = lambda text: print("sim4cv.experiment: %s" % text, file=sys.stderr, flush=True)  # noqa: E731
    if args.executor == "slurm":
        ids = executors.submit_slurm(args.out, args.jobs, args.partition, args.time, args.cpus_per_task,
                                     args.sbatch_line, command, say)
        say("submitted Slurm jobs %s (tasks, then gather); `python3 -m sim4cv.experiment status %s`"
            % (", ".join(ids), args.out))
        if not args.wait:
            return 0
        executors.wait_slurm(ids)
    elif args.executor == "dask":
        executors.run_dask(args.out, args.jobs, args.scheduler, args.retries, say)
    else:
        executors.run_local(args.out, args.jobs, args.daemon)
    if args.executor != "slurm":
        records, written, _ = tasks_gather.gather(args.out, command, time.monotonic() - t0)
        say("%d records; wrote %s in %.1f s" % (len(records), ", ".join(written), time.monotonic() - t0))
    return _print_status(args.out, quiet=True)


def _print_status(out_dir, quiet=False):
    from . import tasks
    st = tasks.status(out_dir)
    names = {t["index"]: t["name"] for t in st["tasks"]}
    print("%d tasks: %d done, %d failed, %d missing" % (len(st["tasks"]), len(st["done"]), len(st["failed"]),
                                                        len(st["missing"])), file=sys.stderr if quiet else sys.stdout)
    if not quiet:
        for i in st["done"]:
            print("done %d %s" % (i, names[i]))
        for i, why in sorted(st["failed"].items()):
            print("failed %d %s: %s" % (i, names[i], why))
        for i in st["missing"]:
            print("missing %d %s" % (i, names[i]))
    return 0 if not st["failed"] and not st["missing"] else 1


def main(argv=None):
    from . import tasks
    argv = sys.argv[1:] if argv is None else argv
    args = _parser().parse_args(argv)
    command = getattr(args, "command_text", None) or "python3 -m sim4cv.experiment " + " ".join(argv)
    try:
        if args.command in ("run", "plan"):
            exp = load(args.file)
            if args.command == "run":
                _check(exp, args)
            planned = tasks.plan(exp, args.out)
            if args.command == "plan":
                print("%d tasks in %s" % (len(planned), os.path.join(os.path.abspath(args.out), tasks.PLAN)))
                return 0
            return _execute(args, exp, command)
        if args.command == "plan-commands":
            planned = tasks.plan_commands(args.file, args.out)
            print("%d tasks in %s" % (len(planned), os.path.join(os.path.abspath(args.out), tasks.PLAN)))
            return 0
        if args.command == "resubmit":
            exp, _ = tasks.load_plan(args.out)
            _check(exp, args)
            return _execute(args, exp, command)
        if args.command == "run-one":
            index = args.index if args.index is not None else tasks.index_from_environment()
            # SIGTERM (scancel, a Ctrl-C'd executor): unwind, so the run stops its trackers and daemon
            signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
            with tasks.TaskEnvironment(index, args.cpus, args.out):
                skipped, error = tasks.run_one(args.out, index, args.daemon)
            print("sim4cv.experiment: task %d %s" % (index, "skipped (done before)" if skipped else
                                                       "failed: " + error if error else "done"), file=sys.stderr)
            return 1 if error else 0
        if args.command == "status":
            return _print_status(args.out)
        from . import tasks_gather
        records, written, st = tasks_gather.gather(args.out, args.command_text or command)
        print("sim4cv.experiment: %d records (%d of %d tasks done); wrote %s"
              % (len(records), len(st["done"]), len(st["tasks"]), ", ".join(written)), file=sys.stderr)
        return 0
    except (ExperimentError, tasks.TaskError) as e:
        print("sim4cv.experiment: error: %s" % e, file=sys.stderr)
        return 2
