"""A one-machine Slurm cluster in a temporary folder, for tests and trials:
munged (its own key and socket), slurmctld and slurmd on loopback with free
ports, state, spool, pid and log files in the folder, SlurmUser=root,
proctrack/linuxproc, task/none, no cgroups, no system services. Everything
is stopped by PID at the end, also on failure.

    with LocalSlurm(cpus=2) as slurm:       # slurm.env: SLURM_CONF for sbatch/squeue/scancel
        subprocess.run(["sbatch", ...], env=slurm.env)

    python3 tests/python/local_slurm.py      # starts one, prints `export SLURM_CONF=...`, Ctrl-C stops it

Needs root and Debian's slurmctld, slurmd, slurm-client and munge (scripts/setup.sh).
"""

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "clients", "python"))
from sim4cv.proctree import environments  # noqa: E402


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class SlurmError(RuntimeError):
    pass


class LocalSlurm:
    def __init__(self, cpus=2, memory_mb=2048):
        self.cpus, self.memory_mb = cpus, memory_mb
        self.procs = []

    def _start(self, name, argv, ready):
        log = open(os.path.join(self.dir, name + ".out"), "w")
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, env=self.env)
        self.procs.append(proc)
        deadline = time.monotonic() + 60
        while not ready():
            if proc.poll() is not None or time.monotonic() > deadline:
                raise SlurmError("%s did not start (%s): %s" % (name, " ".join(argv), self.tail(name)))
            time.sleep(0.2)

    def tail(self, name):
        text = ""
        for path in (os.path.join(self.dir, name + ".out"), os.path.join(self.dir, name + ".log")):
            if os.path.exists(path):
                with open(path, errors="replace") as f:
                    text += f.read()[-2000:]
        return text

    def __enter__(self):
        for binary in ("munged", "slurmctld", "slurmd", "sbatch"):
            if not shutil.which(binary, path=os.environ.get("PATH", "") + ":/usr/sbin"):
                raise SlurmError("no %s: apt-get install slurmctld slurmd slurm-client munge (scripts/setup.sh)"
                                 % binary)
        self.dir = tempfile.mkdtemp(prefix="sim4cv-slurm-")
        os.chmod(self.dir, 0o755)  # munged checks the socket folder's permissions
        try:
            self._configure()
            sock = os.path.join(self.dir, "munge.sock")
            self._start("munged", ["/usr/sbin/munged", "--foreground", "--force", "--socket=" + sock,
                                   "--key-file=" + os.path.join(self.dir, "munge.key"),
                                   "--pid-file=" + os.path.join(self.dir, "munged.pid"),
                                   "--log-file=" + os.path.join(self.dir, "munged.log"),
                                   "--seed-file=" + os.path.join(self.dir, "munged.seed")],
                        lambda: os.path.exists(sock))
            self._start("slurmctld", ["/usr/sbin/slurmctld", "-D", "-c", "-f", self.conf], self._controller_up)
            self._start("slurmd", ["/usr/sbin/slurmd", "-D", "-f", self.conf, "-N", self.node], self._node_idle)
        except BaseException:
            self.stop()
            raise
        return self

    def _configure(self):
        self.node = socket.gethostname().split(".")[0]
        for sub in ("state", "spool"):
            os.makedirs(os.path.join(self.dir, sub))
        key = os.path.join(self.dir, "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        d = self.dir
        self.conf = os.path.join(d, "slurm.conf")
        lines = ["ClusterName=sim4cvtest", "SlurmctldHost=%s(127.0.0.1)" % self.node, "SlurmUser=root",
                 "SlurmdUser=root", "SlurmctldPort=%d" % free_port(), "SlurmdPort=%d" % free_port(),
                 "AuthType=auth/munge", "CredType=cred/munge", "AuthInfo=socket=%s/munge.sock" % d,
                 "StateSaveLocation=%s/state" % d, "SlurmdSpoolDir=%s/spool" % d,
                 "SlurmctldPidFile=%s/slurmctld.pid" % d, "SlurmdPidFile=%s/slurmd.pid" % d,
                 "SlurmctldLogFile=%s/slurmctld.log" % d, "SlurmdLogFile=%s/slurmd.log" % d,
                 "ProctrackType=proctrack/linuxproc", "TaskPlugin=task/none", "JobAcctGatherType=jobacct_gather/none",
                 "AccountingStorageType=accounting_storage/none", "JobCompType=jobcomp/none", "MpiDefault=none",
                 "SchedulerType=sched/backfill", "SelectType=select/cons_tres", "SelectTypeParameters=CR_CPU",
                 "ReturnToService=2", "SlurmdTimeout=300", "InactiveLimit=0", "KillWait=5", "MinJobAge=300",
                 "SchedulerParameters=sched_interval=1", "MaxArraySize=100000",
                 "NodeName=%s NodeAddr=127.0.0.1 CPUs=%d RealMemory=%d State=UNKNOWN"
                 % (self.node, self.cpus, self.memory_mb),
                 "PartitionName=test Nodes=%s Default=YES MaxTime=INFINITE State=UP" % self.node]
        with open(self.conf, "w") as f:
            f.write("\n".join(lines) + "\n")
        self.env = dict(os.environ, SLURM_CONF=self.conf, PATH=os.environ.get("PATH", "") + ":/usr/sbin")

    def _controller_up(self):
        return subprocess.run(["scontrol", "ping"], env=self.env, capture_output=True, text=True).stdout.count("UP") > 0

    def _node_idle(self):
        out = subprocess.run(["sinfo", "-h", "-o", "%t"], env=self.env, capture_output=True, text=True).stdout
        return "idle" in out

    def stop(self):
        for proc in reversed(self.procs):
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(15)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        self.procs = []
        for pid in self._cluster_processes() if hasattr(self, "conf") else []:  # slurmstepd outlives slurmd, and so may a job's tasks
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        shutil.rmtree(self.dir, ignore_errors=True)

    def _cluster_processes(self):
        """PIDs whose environment holds this cluster's SLURM_CONF (slurmstepd and job processes)."""
        marker = ("SLURM_CONF=" + self.conf).encode()
        return [pid for pid, environment in environments() if marker in environment and pid != os.getpid()]

    def __exit__(self, *exc):
        self.stop()


if __name__ == "__main__":
    with LocalSlurm(cpus=int(sys.argv[1]) if len(sys.argv) > 1 else os.cpu_count()) as cluster:
        print("export SLURM_CONF=%s   # Ctrl-C stops the cluster" % cluster.conf, flush=True)
        try:
            signal.pause()
        except KeyboardInterrupt:
            pass
