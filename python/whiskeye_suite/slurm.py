"""The Slurm executor: an array job (a task per world) and a dependent aggregation job."""
import os
import shlex
import subprocess
import sys
import time

from .cli import world_options
from .common import SCRIPT, fail, read_json
from .pipeline import record_failure, world_dir, world_state


SLURM_CALL_S = 120  # a Slurm command that has not answered by then will not (slurmctld unreachable)
SLURM_ENDED = ("COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "PREEMPTED",
               "BOOT_FAIL", "DEADLINE", "REVOKED", "SPECIAL_EXIT")


def slurm(cmd, what):
    """Runs a Slurm client command; its output, or exit 2 with Slurm's own last line of error."""
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=SLURM_CALL_S)
    except subprocess.TimeoutExpired:
        fail(f"{what}: {cmd[0]} did not answer in {SLURM_CALL_S} s (is slurmctld reachable? try sinfo)", 1)
    if r.returncode != 0:
        lines = [x.strip() for x in (r.stderr + r.stdout).splitlines() if x.strip()]
        err = lines[-1] if lines else f"{cmd[0]} exited {r.returncode}"
        fail(f"{what}: {err.replace(cmd[0] + ': error: ', '')}")
    return r.stdout


def cancel(jobs):
    try:
        subprocess.run(["scancel", *jobs], capture_output=True, stdin=subprocess.DEVNULL, timeout=SLURM_CALL_S)
    except subprocess.TimeoutExpired:
        pass


def array_spec(indices):
    """1,2,3,5,7,8 -> '1-3,5,7-8' (sbatch --array)."""
    runs, out = [], []
    for i in indices:
        if runs and i == runs[-1][1] + 1:
            runs[-1][1] = i
        else:
            runs.append([i, i])
    for lo, hi in runs:
        out.append(str(lo) if lo == hi else f"{lo}-{hi}")
    return ",".join(out)


def slurm_states(job_ids):
    """{job id: [state of each of its tasks]} from squeue; a job squeue no longer knows is absent."""
    try:
        r = subprocess.run(["squeue", "--noheader", "--states=all", "--jobs", ",".join(job_ids), "--format=%F %T"],
                           capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=SLURM_CALL_S)
    except subprocess.TimeoutExpired:
        return None  # asked again at the next poll; the deadline bounds it
    if r.returncode != 0:
        return {} if "Invalid job id" in r.stderr else None
    out = {}
    for line in r.stdout.splitlines():
        job, _, state = line.strip().partition(" ")
        out.setdefault(job, []).append(state)
    return out


def run_slurm(a, bins, keys, todo, progress, started_at):
    """Submits `todo` as one array job and the aggregation after it; waits for both (at most
    --timeout s, reporting every world, under every config, as it ends), then returns the
    aggregation's suite.json (a study's study.json)."""
    name = f"suite-{a.family}-s{a.suite_seed}"
    sbatch = ["sbatch", "--parsable", "--chdir", a.results] + (["--partition", a.partition] if a.partition else []) \
        + a.sbatch_args
    what = "sbatch" + (f" --partition {a.partition}" if a.partition else "")
    me = [sys.executable, SCRIPT, *world_options(a, bins), "--executor", "slurm"]
    for i in todo:
        os.makedirs(world_dir(a, i), exist_ok=True)  # the task's output goes there: Slurm makes no folder
    # Held until every world has its placeholder failure: what stands when a task dies before it can
    # say why (a time limit, a node failure); the task replaces it with its record or its own failure.
    array = slurm(sbatch + ["--hold", "--job-name", name, "--array", array_spec(todo) + (f"%{a.jobs}" if a.jobs else ""),
                            "--output", os.path.join(a.results, "world-%3a", "slurm.out"),
                            "--wrap", "exec " + shlex.join(me + ["--run-world"]) + ' "$SLURM_ARRAY_TASK_ID"'],
                  what).strip().split(";")[0]
    agg_out = os.path.join(a.results, "slurm-aggregate.out")
    jobs = [array]
    pending = []  # (world, config) pairs the array runs; a study's pairs already done are reported now
    for i in todo:
        for label, _ in a.variants:
            state, doc = world_state(a, i, keys[label], label)
            if state == "done":
                progress.world(dict(doc, resumed=True))
            else:
                pending.append((i, label))
    try:
        agg = slurm(sbatch + ["--job-name", name + "-aggregate", "--dependency", f"afterany:{array}",
                              "--output", agg_out, "--wrap",
                              "exec " + shlex.join(me + ["--aggregate-only", "--slurm-array", array,
                                                         "--started-at", repr(started_at)])],
                    what + " (aggregation)").strip().split(";")[0]
        jobs.append(agg)
        for i, label in pending:
            record_failure(a, i, keys[label], f"its Slurm array task ended without a result (see {world_dir(a, i)}/slurm.out)",
                           os.path.join(world_dir(a, i), "slurm.out"), label, placeholder=True)
        slurm(["scontrol", "release", array], "scontrol release")
    except SystemExit:
        cancel(jobs)  # no half a suite left queued
        raise
    print(f"suite: {len(todo)} world(s) as Slurm array job {array} ({array_spec(todo)}), aggregation job {agg}",
          file=sys.stderr)
    summary = "study" if a.study else "suite"
    if a.no_wait:
        print(f"suite: not waiting; squeue -j {array},{agg}; the summary will be {a.results}/{summary}.md",
              file=sys.stderr)
        return None
    deadline, poll_s = time.monotonic() + a.timeout, 1.0
    try:
        while True:
            states = slurm_states([array, agg])
            for i, label in list(pending):
                state, doc = world_state(a, i, keys[label], label)
                if state == "done" or (state == "failed" and not doc.get("placeholder")):
                    progress.world(doc)
                    pending.remove((i, label))
            if states is not None and all(s in SLURM_ENDED for s in states.get(agg, [])):  # ended, or gone
                break
            if time.monotonic() > deadline:
                cancel(jobs)
                fail(f"the Slurm jobs {array} (worlds) and {agg} (aggregation) did not end in {a.timeout:g} s "
                     f"(--timeout): cancelled; the same command resumes", 1)
            time.sleep(min(poll_s, max(0.0, deadline - time.monotonic()) + 0.1))
            poll_s = min(poll_s * 1.5, 30.0)
    except KeyboardInterrupt:
        cancel(jobs)
        fail(f"interrupted: Slurm jobs {array} and {agg} cancelled", 130)
    for i, label in pending:  # ended after the last look, or died without a word (the placeholder stands)
        state, doc = world_state(a, i, keys[label], label)
        if doc:
            progress.world(doc)
    doc = read_json(os.path.join(a.results, summary + ".json"))
    if not doc or (doc.get("slurm") or {}).get("aggregate_job") != agg:
        fail(f"the aggregation job {agg} ended without writing {summary}.json (see {agg_out})", 1)
    return doc
