"""Evaluates ViTa-SLAM over a suite of generated worlds (docs/evaluation.md, "The world suite").

  scripts/suite [--worlds N] [--suite-seed S] [--family aliased|stress] [--faults]
                [--scenario normal|kidnap|restart|outliers|long] [--jobs J]
                [--results DIR] [--quick] [--laps K] [--camera-format yuyv|grey|mjpeg] [--config FILE] [--check] [--bin DIR]
                [--executor local|slurm] [--partition P] [--sbatch-args "..."] [--retry-failed]

For each of N worlds drawn from the suite seed (world seed = S * 1000 + i): vita-sim --generate-world,
vita-sim (the simulator log), slamd --replay in the three modes, vita-eval; worlds run in parallel
(--jobs, default: every core), each world's log is deleted once its three replays are evaluated, and
a world already done (same world, options and parameters) is not rerun. Writes DIR/suite.json,
DIR/suite.md and DIR/plots/*.png: per mode ARR, ARCR, ATE, the paper's LEM, EnM and false closures (re-localisations
to an experience made beyond vita-eval's --false-closure-tolerance, 0.25 m or 15 deg, of the robot),
per world also ViTa's experience spacing. Exit status 0 when the suite ran, whatever the numbers;
1 when a world failed to run (its log is named); 2 on bad options.
--check (family aliased; ViTa): prints every target (below) with its measured figure, met or
missed, and exits 1 when one is missed. No target on stress.
--quick: 3 worlds of 1 lap (a smoke test; ARR needs a second lap, so it is n/a there).
--scenario kidnap: every world gets 3 kidnaps drawn after its first lap (the robot put down elsewhere
on its path; odometry does not see it); --scenario restart: every world's map (its run, saved by
slamd) is localised in by 4 more sessions that start at drawn places of the path, 2 laps each
(slamd --map FILE --localise). Both report, per mode, the distance to the first correct localisation
(in laps), the false localisations before it, the time spent LOCALISING and the error after it
(vita-eval, docs/evaluation.md); --check applies the global-localisation issue's targets. With
--quick: 1 world, 1 kidnap (or 1 session of 2 laps), the world's own laps.
--scenario outliers: every world's run is replayed twice more in each mode with a wrong closure added
for every closure the SLAM makes (slamd --inject-wrong-closures: random, far away; group, 5 consecutive
cycles onto an earlier pass elsewhere), and compared with the clean run: ATE against the clean run's,
the wrong links kept (vita-eval's links against the truth); --check applies the back-end issue's
outlier targets. With --quick: 1 world of 2 laps.
--scenario long: every world driven 40 laps (--laps overrides), ATE per window of 4 laps (vita-eval
--ate-window-laps) under the run's alignment; --check applies the back-end issue's long-run targets
(the last window's ATE against the first's, ViTa's whole-run ATE against vision alone's). One simulator
log per job on disk, deleted once replayed. With --quick: 1 world of 8 laps.
--aggregate-only: rewrite suite.json/.md and the plots from the suite seed's worlds already in DIR.
--executor slurm: the same worlds as one `sbatch --array` job (a task per world) and a dependent
aggregation job; waits for them (at most --timeout seconds) unless --no-wait. DIR must be on a
filesystem every node shares, and the programs at the same path on every node.
--retry-failed: run only the worlds whose last run failed (either executor).
--config A.yaml --config B.yaml (a parameter study): every world drawn (with A) and simulated once,
replayed under each config; DIR/study.md compares them side by side, DIR/by-config/<name>/ has each
config's suite summary. --sweep KEY=V1,V2,...: --config with KEY at each value (DIR/configs/).
"""
import argparse
import os
import shlex
import textwrap

from .common import LONG_RUN_LAPS, ROOT, SCENARIOS, fail
from .targets import targets_help


class OneLineErrors(argparse.ArgumentParser):
    """argparse's own errors (an unknown option, a missing value) as one line "suite: ...", exit 2."""
    def error(self, message):
        fail(f"{message} (see --help)")


def parse_args(argv):
    p = OneLineErrors(prog="scripts/suite", description=__doc__.split("\n\n")[0],
                      formatter_class=argparse.RawDescriptionHelpFormatter,
                      epilog=__doc__.split("\n\n", 1)[1] + "\n" + textwrap.fill(targets_help(), 100))
    p.add_argument("--worlds", type=int, default=None, help="number of worlds (default 24; --quick: 3)")
    p.add_argument("--suite-seed", type=int, default=1, help="seed of the suite's worlds (default 1)")
    p.add_argument("--family", default="aliased", help="world family: aliased (default) or stress")
    p.add_argument("--faults", action="store_true", help="every world gets the standard sensor-fault set")
    p.add_argument("--scenario", default="normal", help="normal (default); kidnap: 3 kidnaps a world; restart: "
                   "4 sessions localising in each world's saved map; outliers: wrong closures injected; long: 40 laps")
    p.add_argument("--jobs", type=int, default=None,
                   help="worlds run at once (default: every core; slurm: array tasks at once, default no limit)")
    p.add_argument("--results", default=None, help="results folder (default results/suite/<family>-s<seed>...)")
    p.add_argument("--quick", action="store_true", help="3 worlds, 1 lap each")
    p.add_argument("--laps", type=int, default=None, help="laps of every world (default: the world's own)")
    p.add_argument("--camera-format", default=None, help="the simulated camera's frames: yuyv, grey or mjpeg "
                   "(vita-sim --camera-format; default: the world's, YUYV)")
    p.add_argument("--config", action="append", default=None, help="slamd parameters (default config/slam.yaml); "
                   "given more than once, a parameter study: every world simulated once and replayed under each")
    p.add_argument("--sweep", default=None, metavar="KEY=V1,V2,...", help="a parameter study of one slamd parameter: "
                   "--config (one, or the default) with KEY set to each value, the derived configs in DIR/configs/")
    p.add_argument("--robot", default=os.path.join(ROOT, "config/robot.yaml"), help="robot geometry")
    p.add_argument("--check", action="store_true", help="print every target met or missed; exit 1 when one is missed")
    p.add_argument("--bin", default=None, help="folder with vita-sim, slamd, vita-eval (default: build them)")
    p.add_argument("--aggregate-only", action="store_true", help="only rewrite the summary from DIR's worlds")
    p.add_argument("--no-plots", action="store_true", help="write no plots")
    p.add_argument("--retry-failed", action="store_true", help="run only the worlds whose last run failed")
    p.add_argument("--scratch", default=None, help="folder for the simulator and replay logs (default: the world's "
                   "folder; in a Slurm task $TMPDIR, else /tmp)")
    p.add_argument("--executor", default="local", help="local (default) or slurm")
    p.add_argument("--partition", default=None, help="slurm: the partition (default: the cluster's default)")
    p.add_argument("--sbatch-args", default="", help="slurm: more sbatch options for every job, e.g. \"--time=1:00:00\"")
    p.add_argument("--timeout", type=float, default=86400, help="slurm: give up waiting (cancelling the jobs) "
                   "after this many seconds (default 86400)")
    p.add_argument("--no-wait", action="store_true", help="slurm: submit and exit; the aggregation job writes suite.*")
    # The Slurm jobs call back into this script: one world (an array task), then the aggregation.
    p.add_argument("--run-world", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--slurm-array", default=None, help=argparse.SUPPRESS)
    p.add_argument("--started-at", type=float, default=None, help=argparse.SUPPRESS)
    p.add_argument("--world-config", default=None, help=argparse.SUPPRESS)  # a study's worlds are drawn with it
    a = p.parse_args(argv)
    if a.family not in ("aliased", "stress"):
        fail(f"--family: unknown family '{a.family}' (aliased or stress)")
    if a.scenario not in SCENARIOS:
        fail(f"--scenario: unknown scenario '{a.scenario}' (normal, kidnap, restart, outliers or long)")
    if a.executor not in ("local", "slurm"):
        fail(f"--executor: unknown executor '{a.executor}' (local or slurm)")
    if a.worlds is None:
        a.worlds = (1 if a.scenario != "normal" else 3) if a.quick else 24
    if a.quick and a.laps is None and a.scenario in ("normal", "outliers"):
        a.laps = 1 if a.scenario == "normal" else 2  # closures (and so wrong ones) need a second lap
    if a.scenario == "long" and a.laps is None:
        a.laps = 8 if a.quick else LONG_RUN_LAPS  # at least two windows of 4 laps
    if a.laps is not None and a.scenario == "kidnap":
        fail("--laps: a kidnap scenario runs each world's own laps (its kidnaps are drawn for them)")
    if not 1 <= a.worlds <= 10000:
        fail(f"--worlds: {a.worlds} is not in 1..10000")
    if a.jobs is not None and a.jobs < 1:
        fail(f"--jobs: {a.jobs} is not a positive number")
    if a.jobs is None and a.executor == "local":
        a.jobs = os.cpu_count() or 1
    if a.camera_format is not None and a.camera_format not in ("yuyv", "grey", "mjpeg"):
        fail(f"--camera-format: unknown format '{a.camera_format}' (yuyv, grey or mjpeg)")
    if a.laps is not None and not 1 <= a.laps <= 10000:
        fail(f"--laps: {a.laps} is not in 1..10000 (the world file's bounds)")
    if not 0 <= a.suite_seed < 2**40:
        fail(f"--suite-seed: {a.suite_seed} is not in 0..2^40")
    if a.timeout <= 0:
        fail(f"--timeout: {a.timeout:g} is not a positive number of seconds")
    if a.executor == "local":
        for opt in ("partition", "sbatch_args", "no_wait"):
            if getattr(a, opt):
                fail(f"--{opt.replace('_', '-')}: only with --executor slurm")
    if a.aggregate_only and a.retry_failed:
        fail("--retry-failed: runs worlds, --aggregate-only runs none")
    if a.run_world is not None and not 1 <= a.run_world <= a.worlds:
        fail(f"--run-world: {a.run_world} is not in 1..{a.worlds}")
    try:
        a.sbatch_args = shlex.split(a.sbatch_args)
    except ValueError as e:
        fail(f"--sbatch-args: {e}")
    configs = a.config or [os.path.join(ROOT, "config/slam.yaml")]
    for path in configs + [a.robot] + ([a.world_config] if a.world_config else []):
        if not os.path.isfile(path):
            fail(f"--{'robot' if path == a.robot else 'config'}: {path} is not a file")
    configs = [os.path.abspath(c) for c in configs]
    a.robot = os.path.abspath(a.robot)
    a.config = configs[0]
    a.study = len(configs) > 1 or a.sweep is not None
    if a.sweep is not None:
        if len(configs) > 1:
            fail("--sweep: varies one --config, not several")
        a.sweep = parse_sweep(a.sweep)
        a.variants = None  # derived by study.derive_sweep once the programs are known
    else:
        a.variants = variants_of(configs) if a.study else [(None, a.config)]
    a.world_config = os.path.abspath(a.world_config) if a.world_config else a.config
    if a.results is None:
        scenario = "" if a.scenario == "normal" else f"-{a.scenario}"
        name = f"{a.family}{'-faults' if a.faults else ''}{scenario}-s{a.suite_seed}{'-quick' if a.quick else ''}"
        name += f"-{a.camera_format}" if a.camera_format else ""
        a.results = os.path.join(ROOT, "results", "suite", name)
    a.results = os.path.abspath(a.results)
    if a.scratch is not None:
        a.scratch = os.path.abspath(a.scratch)
    return a


LABEL_CHARS = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._=+-")


def variants_of(configs):
    """A study's configs by label: each file's name without .yaml (its results' folder name)."""
    out = []
    for path in configs:
        label = os.path.basename(path)
        label = label[:-5] if label.endswith(".yaml") else label
        if not label or not set(label) <= LABEL_CHARS or label.startswith("world-"):
            fail(f"--config: {path}: a study names each config by its file name, and '{label}' cannot name a folder "
                 "(letters, digits, . _ = + -; not world-*)")
        if label in (x for x, _ in out):
            fail(f"--config: two configs named '{label}' (a study names each by its file name)")
        out.append((label, path))
    return out


def parse_sweep(text):
    """'KEY=V1,V2,...' -> (KEY, [V1, V2, ...]): at least two distinct values."""
    key, eq, values = text.partition("=")
    values = [v.strip() for v in values.split(",")]
    if not eq or not key or "." not in key or any(not v for v in values):
        fail(f"--sweep: '{text}' is not KEY=V1,V2,... (e.g. slam.match.threshold_visual=0.08,0.10,0.12)")
    if len(set(values)) < 2 or len(set(values)) != len(values):
        fail(f"--sweep: '{text}' needs two or more distinct values")
    return key, values


def world_options(a, bins):
    """The options that make the suite's worlds, spelled out: what the Slurm jobs are given, and the
    command that reruns the suite."""
    out = ["--worlds", str(a.worlds), "--suite-seed", str(a.suite_seed), "--family", a.family,
           "--results", a.results]
    for _, config in a.variants:  # a sweep's derived configs: the tasks need not know the sweep
        out += ["--config", config]
    out += ["--robot", a.robot, "--bin", bins]
    if a.study:
        out += ["--world-config", a.world_config]
    if a.faults:
        out.append("--faults")
    if a.scenario != "normal":
        out += ["--scenario", a.scenario]
    if a.quick:
        out.append("--quick")
    if a.laps:
        out += ["--laps", str(a.laps)]
    if a.camera_format:
        out += ["--camera-format", a.camera_format]
    if a.no_plots:
        out.append("--no-plots")
    if a.scratch:
        out += ["--scratch", a.scratch]
    return out


def executor_options(a):
    """The options that say how the worlds run, spelled out."""
    if a.executor == "local":
        return ["--jobs", str(a.jobs)]
    out = ["--executor", "slurm"] + (["--jobs", str(a.jobs)] if a.jobs else [])
    if a.partition:
        out += ["--partition", a.partition]
    if a.sbatch_args:
        out += ["--sbatch-args", shlex.join(a.sbatch_args)]
    return out
