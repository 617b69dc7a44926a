"""The suite's command: parse, pick the worlds to run, run them on an executor, aggregate, report."""
import os
import shutil
import subprocess
import sys
import time

from .cli import parse_args
from .common import PROGRAMS, ROOT, fail
from .local import run_local, run_one
from .pipeline import collect, world_key, world_state
from .report import Progress, aggregate, report
from .slurm import run_slurm


def build():
    subprocess.run([os.path.join(ROOT, "scripts/install-deps")], check=True)
    subprocess.run(["cmake", "-S", ROOT, "-B", os.path.join(ROOT, "build"), "-G", "Ninja",
                    "-DCMAKE_BUILD_TYPE=RelWithDebInfo"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", os.path.join(ROOT, "build"), "-j", str(os.cpu_count() or 1), "--target",
                    "vita-sim", "slamd", "vita-eval"], check=True)
    return os.path.join(ROOT, "build", "bin")


def check_programs(bins):
    for tool in PROGRAMS:
        if not os.access(os.path.join(bins, tool), os.X_OK):
            fail(f"--bin: {os.path.join(bins, tool)} is not an executable")


def main(argv):
    a = parse_args(argv)
    os.makedirs(a.results, exist_ok=True)
    started_at = a.started_at or time.time()
    if a.aggregate_only:
        key = None
        if a.slurm_array:  # the aggregation job: only what this suite's options and programs made
            check_programs(a.bin)
            key = world_key(a, a.bin)
        records, failed = collect(a, key)
        if not records and not failed:
            fail(f"{a.results}: no finished world to aggregate")
        doc = aggregate(a, records, failed, time.time() - started_at)
        if a.slurm_array:
            print(f"suite: {a.results}/suite.md, suite.json, plots/ ({len(records)} worlds, {len(failed)} failed)")
            return 0
        return report(a, doc, a.bin or os.path.join(ROOT, "build", "bin"))
    if a.executor == "slurm" and a.run_world is None and not shutil.which("sbatch"):
        fail("--executor slurm: sbatch is not on the PATH (install Slurm's client commands, "
             "e.g. Debian's slurm-client, or load the cluster's Slurm module)")
    bins = os.path.abspath(a.bin or build())
    check_programs(bins)
    key = world_key(a, bins)
    if a.run_world is not None:  # an array task: one world, its outcome on stdout (the task's log)
        rec = run_one(a, bins, a.run_world, key)
        print(f"suite: world {a.run_world} " + (f"FAILED: {rec['failed']}" if "failed" in rec else
                                                 "resumed" if rec.get("resumed") else "done"))
        return 1 if "failed" in rec else 0

    states = {i: world_state(a, i, key) for i in range(1, a.worlds + 1)}
    done = {i: doc for i, (state, doc) in states.items() if state == "done"}
    todo = [i for i, (state, _) in states.items() if state == "failed" or (state == "todo" and not a.retry_failed)]
    progress = Progress(len(done) + len(todo), sys.stderr.isatty())
    print(f"suite: {a.worlds} worlds ({a.family}{', faults' if a.faults else ''}, suite seed {a.suite_seed}) "
          + (f"with {a.jobs} jobs" if a.executor == "local" else "on Slurm") + f" -> {a.results}"
          + (f"; retrying {len(todo)} failed" if a.retry_failed else ""), file=sys.stderr)
    for doc in done.values():
        progress.world(dict(doc, resumed=True))
    if a.executor == "slurm" and todo:
        doc = run_slurm(a, bins, key, todo, progress, started_at)
        if doc is None:
            return 0
    else:
        run_local(a, bins, key, todo, progress)
        doc = aggregate(a, *collect(a, key), time.time() - started_at)
    return report(a, doc, bins)
