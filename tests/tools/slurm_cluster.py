"""A throw-away single-node Slurm cluster for tests: munged, slurmctld and slurmd of Debian's packages,
each in the foreground under this process, every file (key, sockets, spool, state, logs) under one
temporary folder, loopback only. Nothing under /etc, /run or /var is read or written.

  with SlurmCluster() as c:          # raises ClusterError when a daemon does not come up
      env = c.env()                  # SLURM_CONF set: sbatch, squeue, ... talk to this cluster
      ...
  # every daemon (and job step) is gone here, even after an exception; c.leftovers() says otherwise
"""
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time

DAEMONS = ("munged", "slurmctld", "slurmd", "slurmstepd")


class ClusterError(Exception):
    pass


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pids_named(names, zombies=False):
    """The processes whose name is one of `names` (what pgrep -x would list, zombies if asked)."""
    return {pid for pid in all_pids() if read_proc(pid, "comm").strip() in names and (zombies or not zombie(pid))}


def zombie(pid):
    """Exited and waiting to be reaped (by init, for a daemon's orphans): nothing left to stop."""
    return read_proc(pid, "stat").rpartition(")")[2].split()[:1] == ["Z"]


def all_pids():
    return [int(p) for p in os.listdir("/proc") if p.isdigit()]


def read_proc(pid, what):
    try:
        with open(f"/proc/{pid}/{what}", "rb") as f:
            return f.read().decode(errors="replace")
    except OSError:
        return ""


class SlurmCluster:
    def __init__(self, partition="debug", start_timeout_s=60):
        self.partition, self.start_timeout_s = partition, start_timeout_s
        self.node = socket.gethostname().split(".")[0]
        self.procs = []

    def env(self):
        # The marker goes to every daemon, job step and job (sbatch exports the environment): what
        # carries it is this cluster's, and teardown ends exactly that.
        return dict(os.environ, SLURM_CONF=self.conf, WHISKEYE_TEST_CLUSTER=self.tmp)

    def __enter__(self):
        missing = [p for p in ("munged", "slurmctld", "slurmd", "sbatch", "sinfo") if not shutil.which(p)]
        if missing:
            raise ClusterError(f"not installed: {', '.join(missing)} (scripts/install-deps installs Slurm and munge)")
        self.before = pids_named(DAEMONS, zombies=True)  # someone else's daemons are not ours to check or stop
        self.tmp = tempfile.mkdtemp(prefix="slurm_cluster_")
        self.conf = os.path.join(self.tmp, "slurm.conf")
        try:
            self._start()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def _path(self, *parts):
        return os.path.join(self.tmp, *parts)

    def _spawn(self, name, cmd):
        log = open(self._path(f"{name}.out"), "w")
        # Its own process group, so that teardown reaches whatever the daemon forked.
        p = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             env=self.env(), start_new_session=True)
        log.close()
        self.procs.append((name, p))
        return p

    def _wait(self, what, ready):
        deadline = time.monotonic() + self.start_timeout_s
        while time.monotonic() < deadline:
            for name, p in self.procs:
                if p.poll() is not None:
                    raise ClusterError(f"{name} exited {p.returncode} while waiting for {what}: "
                                       + self._tail(name))
            if ready():
                return
            time.sleep(0.2)
        raise ClusterError(f"timed out after {self.start_timeout_s} s waiting for {what}")

    def _tail(self, name):
        for f in (f"{name}.out", f"{name}.log"):
            try:
                with open(self._path(f)) as fh:
                    lines = fh.read().strip().splitlines()
                if lines:
                    return lines[-1]
            except OSError:
                pass
        return "(no output)"

    def _start(self):
        for d in ("munge", "state", "spool"):
            os.makedirs(self._path(d), mode=0o700)
        key = self._path("munge", "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        self.munge_socket = self._path("munge", "munge.socket")
        self._spawn("munged", ["munged", "--foreground", "--force", "--key-file", key, "--socket", self.munge_socket,
                               "--pid-file", self._path("munge", "munged.pid"), "--log-file",
                               self._path("munge", "munged.log"), "--seed-file", self._path("munge", "munged.seed")])
        self._wait("munged's socket", lambda: os.path.exists(self.munge_socket))

        cpus = os.cpu_count() or 1
        with open("/proc/meminfo") as f:
            mem_mb = int(next(l for l in f if l.startswith("MemTotal:")).split()[1]) // 1024
        with open(self.conf, "w") as f:
            f.write(f"""# A single-node test cluster (tests/tools/slurm_cluster.py)
ClusterName=whiskeye-test
SlurmctldHost=localhost
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket={self.munge_socket}
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
SwitchType=switch/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
ReturnToService=2
MailProg=/bin/true
StateSaveLocation={self._path("state")}
SlurmdSpoolDir={self._path("spool")}
SlurmctldPidFile={self._path("slurmctld.pid")}
SlurmdPidFile={self._path("slurmd.pid")}
SlurmctldLogFile={self._path("slurmctld.log")}
SlurmdLogFile={self._path("slurmd.log")}
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
NodeName={self.node} NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={mem_mb * 9 // 10} State=UNKNOWN
PartitionName={self.partition} Nodes={self.node} Default=YES MaxTime=INFINITE State=UP
""")
        self._spawn("slurmctld", ["slurmctld", "-D", "-i", "-f", self.conf])
        self._wait("slurmctld", lambda: self._run(["sinfo", "-h"]).returncode == 0)
        self._spawn("slurmd", ["slurmd", "-D", "-f", self.conf, "-N", self.node])
        self._wait(f"node {self.node} idle",
                   lambda: self._run(["sinfo", "-h", "-N", "-o", "%T"]).stdout.strip() == "idle")

    def _run(self, cmd):
        return subprocess.run(cmd, capture_output=True, text=True, env=self.env(), timeout=30)

    def leftovers(self):
        """This cluster's processes (daemons, job steps, jobs) still alive, but this one."""
        marker = f"WHISKEYE_TEST_CLUSTER={self.tmp}"
        return sorted(p for p in all_pids() if p != os.getpid() and not zombie(p)
                      and marker in read_proc(p, "environ").split("\0"))

    def new_daemons(self):
        """munged or Slurm daemons alive now that were not before the cluster started (pgrep's view)."""
        return sorted(pids_named(DAEMONS) - self.before)

    def __exit__(self, *exc):
        if any(p.poll() is None for name, p in self.procs if name == "slurmctld"):
            try:  # no job outlives the cluster
                self._run(["scancel", "--full", "--partition", self.partition])
            except (OSError, subprocess.TimeoutExpired):
                pass
        for name, p in reversed(self.procs):
            for sig, wait_s in ((signal.SIGTERM, 10), (signal.SIGKILL, 5)):
                try:
                    os.killpg(p.pid, sig)
                except ProcessLookupError:
                    pass
                try:
                    p.wait(wait_s)
                    break
                except subprocess.TimeoutExpired:
                    continue
        # A job step forked by slurmd leaves slurmd's process group; nothing of this cluster survives.
        deadline = time.monotonic() + 10
        while self.leftovers() and time.monotonic() < deadline:
            for pid in self.leftovers():
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            time.sleep(0.2)
        # What init has still to reap: gone in a moment, and pgrep would list it until then.
        while pids_named(DAEMONS, zombies=True) - self.before and time.monotonic() < deadline:
            time.sleep(0.2)
        shutil.rmtree(self.tmp, ignore_errors=True)
        return False
