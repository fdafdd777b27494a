"""The `sim4cv` command: one entry point for the package's tools.

    sim4cv experiment run FILE.yaml --out DIR        scripted tracking experiments
    sim4cv sequences generate --out DIR ...          UAV123-format tracking sequences
    sim4cv ope --sequences DIR --results DIR ...     one-pass evaluation of trackers
    sim4cv driving evaluate --maps test --out DIR    the driving case study
    sim4cv guided layout --base MAP ...              guided driving (goals at junctions)
    sim4cv COMMAND --help                            the command's own options

Each command is its module's main(argv), unchanged: it takes whatever that module's command
line takes (its subcommands too, present and future), and `python3 -m sim4cv.MODULE` keeps
working. Exit status: 0 done, 1 the work failed (a run, an evaluation, a daemon that would
not start; the message says why), 2 a usage error (an unknown command or option, a bad
argument). Tools that start their own daemon use $SIM4CVD, else an installed sim4cvd
(sim4cv.daemon.daemon_path).
"""

import importlib
import sys
from typing import List, Optional

# command -> (module whose main(argv) it runs, what it does)
COMMANDS = {
    "experiment": ("experiment_cli", "scripted tracking experiments from YAML files: runs, resume, reports"),
    "sequences": ("sequences_cli", "UAV123-format tracking sequences: generate, attributes, maps"),
    "ope": ("ope_cli", "one-pass evaluation (OPE) of tracker results: success and precision"),
    "driving": ("driving", "the driving case study: generate, train, evaluate, drive, human, ..."),
    "guided": ("driving_guided", "guided driving: layout, generate, evaluate, probe"),
}


def version_line() -> str:
    try:
        from importlib.metadata import PackageNotFoundError, version
        try:
            package = version("sim4cv")
        except PackageNotFoundError:
            package = "(not installed: run from the source tree)"
    except ImportError:
        package = "(unknown)"
    from .daemon import DaemonError, daemon_path
    try:
        daemon = daemon_path()
    except DaemonError as e:
        daemon = "not found (%s)" % e
    return "sim4cv %s\nsim4cvd: %s" % (package, daemon)


def usage() -> str:
    lines = [__doc__.split("\n\n")[0].replace("The `sim4cv` command: ", ""), "",
             "usage: sim4cv COMMAND [ARGS...] | sim4cv --help | sim4cv --version", "", "commands:"]
    lines += ["  %-11s %s" % (name, summary) for name, (_, summary) in COMMANDS.items()]
    lines += ["", "sim4cv COMMAND --help shows a command's options. Exit status: 0 done, 1 failed, 2 usage error."]
    return "\n".join(lines)


def run_module(module_name: str, argv: List[str]) -> int:
    module = importlib.import_module("." + module_name, __package__)
    try:
        status = module.main(argv)
    except SystemExit as e:  # argparse: 0 after --help, 2 on a usage error
        status = e.code
    except KeyboardInterrupt:
        return 1
    if status is None:
        return 0
    if isinstance(status, int):
        return status
    print(status, file=sys.stderr)  # sys.exit("message") convention
    return 1


def main(argv: Optional[List[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        print(usage(), file=sys.stderr)
        return 2
    command, rest = argv[0], argv[1:]
    if command in ("-h", "--help", "help") and not rest:
        print(usage())
        return 0
    if command == "help":  # sim4cv help COMMAND
        command, rest = rest[0], ["--help"]
    if command == "--version":
        print(version_line())
        return 0
    if command not in COMMANDS:
        print("sim4cv: unknown command %r\n\n%s" % (command, usage()), file=sys.stderr)
        return 2
    return run_module(COMMANDS[command][0], rest)


if __name__ == "__main__":
    sys.exit(main())
