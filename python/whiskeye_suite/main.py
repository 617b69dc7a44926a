"""The suite's command: parse, pick the worlds to run, run them on an executor, aggregate, report."""
import os
import shutil
import subprocess
import sys
import time

from .cli import parse_args
from .common import PROGRAMS, ROOT, NotJson, fail
from .local import run_local, run_one
from .pipeline import collect, world_keys, world_state
from .records import BadRecord
from .report import Progress, aggregate, report
from .slurm import run_slurm
from .study import aggregate_study, derive_sweep


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


def summarise(a, keys, wall_s):
    """The summary of what DIR holds: a suite's suite.*, or a study's study.* and by-config/."""
    if a.study:
        return aggregate_study(a, keys, wall_s)
    return aggregate(a, *collect(a, keys[None]), wall_s)


def main(argv):
    """A results file that is no record of the suite's (BadRecord), or a summary that JSON cannot
    hold (NotJson): one line naming the file and the field, exit 1, nothing summarised from it."""
    try:
        return run(argv)
    except (BadRecord, NotJson) as e:
        fail(str(e), 1)


def run(argv):
    a = parse_args(argv)
    os.makedirs(a.results, exist_ok=True)
    started_at = a.started_at or time.time()
    if a.aggregate_only:
        keys = None
        if a.slurm_array:  # the aggregation job: only what this suite's options and programs made
            check_programs(a.bin)
        if a.sweep:
            a.variants = derive_sweep(a, a.bin)
        if a.slurm_array:
            keys = world_keys(a, a.bin)
        keys = keys or {label: None for label, _ in a.variants}
        if not any(collect(a, key, label) != ([], []) for label, key in keys.items()):
            fail(f"{a.results}: no finished world to aggregate")
        for label, key in keys.items():
            if key is None:  # any run's records: they must be one run's (options, config, programs)
                records, failed = collect(a, None, label)
                runs = {doc.get("key") for doc in records + failed}
                if len(runs) > 1:
                    fail(f"{a.results}: its worlds{f' [{label}]' if label else ''} come from {len(runs)} different "
                         "runs (other options, config or programs): one summary must not mix them; run the "
                         "suite over it again")
        doc = summarise(a, keys, time.time() - started_at)
        if a.slurm_array:
            name = "study" if a.study else "suite"
            print(f"suite: {a.results}/{name}.md, {name}.json, plots/ ({len(doc['worlds'])} worlds, "
                  f"{len(doc['failed_worlds'])} failed)")
            return 0
        return report(a, doc, a.bin or os.path.join(ROOT, "build", "bin"))
    if a.executor == "slurm" and a.run_world is None and not shutil.which("sbatch"):
        fail("--executor slurm: sbatch is not on the PATH (install Slurm's client commands, "
             "e.g. Debian's slurm-client, or load the cluster's Slurm module)")
    bins = os.path.abspath(a.bin or build())
    check_programs(bins)
    if a.sweep:
        a.variants = derive_sweep(a, bins)
    keys = world_keys(a, bins)
    if a.run_world is not None:  # an array task: one world, its outcome on stdout (the task's log)
        docs = run_one(a, bins, a.run_world, keys)
        for doc in docs:
            print(f"suite: world {a.run_world}" + (f" [{doc['config']}]" if doc.get("config") else "") + " "
                  + (f"FAILED: {doc['failed']}" if "failed" in doc else "resumed" if doc.get("resumed") else "done"))
        return 1 if any("failed" in doc for doc in docs) else 0

    # A world is done when every config has its record; it runs again when one failed or (unless
    # --retry-failed) has none.
    states = {i: [world_state(a, i, keys[label], label) for label, _ in a.variants] for i in range(1, a.worlds + 1)}
    done = {i: [doc for _, doc in s] for i, s in states.items() if all(state == "done" for state, _ in s)}
    todo = [i for i, s in states.items() if i not in done and (
        any(state == "failed" for state, _ in s) or not a.retry_failed)]
    progress = Progress(len(a.variants) * (len(done) + len(todo)), sys.stderr.isatty())
    configs = f", {len(a.variants)} configs" if a.study else ""
    print(f"suite: {a.worlds} worlds ({a.family}{', faults' if a.faults else ''}, suite seed {a.suite_seed}{configs}) "
          + (f"with {a.jobs} jobs" if a.executor == "local" else "on Slurm") + f" -> {a.results}"
          + (f"; retrying {len(todo)} failed" if a.retry_failed else ""), file=sys.stderr)
    for docs in done.values():
        for doc in docs:
            progress.world(dict(doc, resumed=True))
    if a.executor == "slurm" and todo:
        doc = run_slurm(a, bins, keys, todo, progress, started_at)
        if doc is None:
            return 0
    else:
        run_local(a, bins, keys, todo, progress)
        doc = summarise(a, keys, time.time() - started_at)
    return report(a, doc, bins)
