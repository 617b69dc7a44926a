#!/usr/bin/env python3
"""Every script of scripts/ has a correct --help (exit 0, its own usage line) and turns a bad command
line into one line "<script>: <reason>" and exit 2, before it builds, installs or runs anything."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SCRIPTS = os.path.join(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "../.."),
                       "scripts")

# Per script: bad command lines (each must fail at once). lcm-spy passes what it does not know to
# lcm-spy itself, so only its --help is ours.
BAD = {
    "demo": [["--bogus"], ["--seed"], ["--seed", "2", "--laps"], ["--world", "/no/such.yaml"],
             ["--config", "/no/such.yaml"]],
    "demo-kidnap": [["--bogus"], ["--seed"], ["--at"], ["--seed", "2", "--to-angle"]],
    "seeds": [["--bogus"], ["--world"], ["--world", "/no/such.yaml"], ["--config", "/no/such.yaml"]],
    "fuzz": [["--bogus"], ["--minutes"], ["--seconds", "x"], ["no_such_target"]],
    "suite": [["--bogus"], ["--worlds"], ["--worlds", "x"], ["--scenario", "wander"], ["--camera-format", "png"]],
    "install-deps": [["--bogus"]],
    "netns-run": [[]],
    "test": [["--no-such-stage"]],
    "lcm-spy": [],
    "bench": [["--bogus"], ["--filter"], ["--repetitions", "x"], ["--only", "no-such-bench"], ["--table"],
              ["--table", "/no/such.json"], ["--table", "/etc/hostname"]],
    "replay-speed": [["--bogus"], ["--runs", "0"], ["--mode", "x"], ["--log", "/no/such/log"],
                     ["--camera-format", "png"], ["--camera-format", "mjpeg", "--log", "/etc/hostname"],
                     ["--suite-world", "x"], ["--suite-seed", "-1"], ["--suite-world", "1", "--log", "/etc/hostname"],
                     ["--against"], ["--against", "/no/such/build", "--log", "/etc/hostname"]],
}


# What a script must not reach before it refuses its command line: a build or a package install.
# These stand-ins fail at once, so a check that stops working fails its test in a second with this
# line, instead of building the tree until the time-out.
STUBS = tempfile.mkdtemp(prefix="scripts-cli-stubs-")
for tool in ("cmake", "ninja", "apt-get"):
    with open(os.path.join(STUBS, tool), "w") as f:
        f.write(f"#!/bin/sh\necho '{tool}: reached by a command line that should have been refused' >&2\nexit 97\n")
    os.chmod(os.path.join(STUBS, tool), 0o755)
ENV = dict(os.environ, PATH=STUBS + os.pathsep + os.environ.get("PATH", ""))


def run(name, args, cwd=None):
    return subprocess.run([os.path.join(SCRIPTS, name)] + args, capture_output=True, text=True, timeout=60,
                          stdin=subprocess.DEVNULL, cwd=cwd, env=ENV)


class Scripts(unittest.TestCase):
    def test_every_script_is_covered(self):
        scripts = [n for n in os.listdir(SCRIPTS) if os.path.isfile(os.path.join(SCRIPTS, n))]
        self.assertEqual(sorted(scripts), sorted(BAD))

    def test_a_relative_path_is_the_callers_not_the_repositorys(self):
        """Run from another directory, `config/slam.yaml` names that directory's file (there is none),
        not the repository's, and the error says which file it looked for."""
        with tempfile.TemporaryDirectory() as d:
            for name, option, what in (("demo", "--config", "configuration"), ("demo", "--world", "world"),
                                       ("seeds", "--config", "configuration"), ("seeds", "--world", "world")):
                with self.subTest(script=name, option=option):
                    path = "config/slam.yaml" if option == "--config" else "config/worlds/aliased_arena.yaml"
                    r = run(name, [option, path], cwd=d)
                    self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
                    self.assertEqual(r.stderr, f"{name}: no {what} file '{d}/{path}'\n")
        r = run("seeds", ["--world", "no-such-world.yaml"], cwd="/")  # /no-such-world.yaml, not //
        self.assertEqual(r.stderr, "seeds: no world file '/no-such-world.yaml'\n")

    def test_help_exits_zero_with_a_usage_line(self):
        for name in BAD:
            for flag in ("--help", "-h"):
                with self.subTest(script=name, flag=flag):
                    r = run(name, [flag])
                    self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                    self.assertIn(f"scripts/{name}", r.stdout, r.stdout)
                    self.assertEqual(r.stderr, "")

    def test_a_bad_command_line_is_one_line_and_exit_two(self):
        for name, cases in BAD.items():
            for args in cases:
                with self.subTest(script=name, args=args):
                    r = run(name, args)
                    self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
                    self.assertEqual(r.stdout, "")
                    self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)
                    self.assertTrue(r.stderr.startswith(f"{name}: "), r.stderr)


class FuzzSeeds(unittest.TestCase):
    # The inputs of past findings live apart from the generated seeds: --make-seeds, which remakes
    # fuzz/corpus/ from scratch, must not lose them, and every run must start from them.
    def test_make_seeds_leaves_the_regression_inputs_alone_and_every_run_reads_them(self):
        root = os.path.dirname(SCRIPTS)
        with open(os.path.join(SCRIPTS, "fuzz")) as f:
            text = f.read()
        make_seeds = text[text.index('if [ "$make_seeds" = 1 ]'):]
        make_seeds = make_seeds[:make_seeds.index("exit 0")]
        self.assertIn("rm -rf fuzz/corpus", make_seeds)
        self.assertNotIn("regressions", make_seeds)
        self.assertIn('seeds+=("fuzz/regressions/$t")', text)
        targets = text[text.index("targets_all=("):].split(")")[0].split("(")[1].split()
        regressions = os.path.join(root, "fuzz", "regressions")
        self.assertTrue(os.listdir(regressions))
        for target in os.listdir(regressions):
            self.assertIn(target, targets, f"fuzz/regressions/{target}/ is no target's")
            self.assertTrue(os.listdir(os.path.join(regressions, target)), target)


class InstallDepsProfiles(unittest.TestCase):
    def test_the_demo_profile_is_the_build_and_libraries_without_what_only_the_tests_need(self):
        demo = run("install-deps", ["--demo", "--list"])
        every = run("install-deps", ["--list"])
        self.assertEqual((demo.returncode, every.returncode), (0, 0), demo.stderr + every.stderr)
        demo, every = demo.stdout.split(), every.stdout.split()
        self.assertEqual(len(set(every)), len(every), "a package listed twice")
        self.assertLess(set(demo), set(every))
        for needed in ("build-essential", "cmake", "liblcm-dev", "liblcm-bin", "libopencv-imgcodecs-dev",
                       "libturbojpeg0-dev"):
            self.assertIn(needed, demo)
        for heavy in ("default-jdk-headless", "chromium", "qemu-system-x86", "linux-source", "slurmctld", "clang",
                      "libgtest-dev"):
            self.assertNotIn(heavy, demo)


class BenchTable(unittest.TestCase):
    def test_a_results_file_becomes_one_markdown_table_per_binary_with_medians_only(self):
        import json
        doc = {"date": "2026-12-04T12:00:00Z", "git_describe": "abc123", "build_type": "RelWithDebInfo",
               "compiler": "/usr/bin/c++", "cpus": 2, "cpu": "Some CPU", "load_average_before": [0.5, 0.4, 0.3],
               "load_average_after": [1.0, 0.9, 0.8],
               "binaries": {"vita-bench": {"benchmarks": [
                   {"name": "BM_A/10_mean", "run_type": "aggregate", "aggregate_name": "mean", "real_time": 9.0,
                    "cpu_time": 9.0, "time_unit": "us"},
                   {"name": "BM_A/10_median", "run_type": "aggregate", "aggregate_name": "median", "real_time": 2.5,
                    "cpu_time": 2.25, "time_unit": "us", "label": "avx512bw", "per_template": 0.125},
                   {"name": "BM_B", "run_type": "iteration", "real_time": 7.0, "cpu_time": 6.0, "time_unit": "ms",
                    "error_occurred": True, "error_message": "this CPU lacks the instructions"}]},
                   "viewer-bench": None}}
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "results.json"), "w") as f:
                json.dump(doc, f)
            r = run("bench", ["--table", "results.json"], cwd=d)  # the caller's directory's file
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertEqual(lines[0], "2026-12-04T12:00:00Z, `abc123`, RelWithDebInfo build, /usr/bin/c++, 2 × Some CPU; "
                                   "load average 0.50, 0.40, 0.30 before, 1.00, 0.90, 0.80 after.")
        self.assertIn("| `BM_A/10_median` | 2.5 us | 2.25 us | avx512bw, per_template 0.125 |", lines)
        self.assertIn("| `BM_B` | — | — | skipped: this CPU lacks the instructions |", lines)
        self.assertNotIn("mean", r.stdout)
        self.assertIn("(no benchmark selected)", lines)


class ReplaySpeed(unittest.TestCase):
    def test_against_runs_the_builds_alternately_and_gives_the_cpu_ratio(self):
        """Two stand-in slamds (a shell loop that burns CPU, then prints slamd's last line), named by
        paths relative to the caller's directory: the rounds alternate --bin's and --against's, and the
        ratio of their CPU medians is printed."""
        import re
        with tempfile.TemporaryDirectory() as d:
            log = os.path.join(d, "x.lcmlog")
            with open(log, "wb") as f:
                f.write(b"\0" * 64)
            dirs = {}
            for name, loops in (("fast", 60000), ("slow", 180000)):
                dirs[name] = os.path.join(d, name)
                os.mkdir(dirs[name])
                path = os.path.join(dirs[name], "slamd")
                with open(path, "w") as f:
                    f.write("#!/bin/bash\ni=0; while [ $i -lt %d ]; do i=$((i+1)); done\n"
                            "echo 'slamd: replayed 100.0 s of data in 0.10 s (1000x real time)' >&2\n" % loops)
                os.chmod(path, 0o755)
            # relative to the directory it is started in, as any command's paths
            r = run("replay-speed", ["--log", "x.lcmlog", "--runs", "3", "--bin", "fast", "--against", "slow"], cwd=d)
        self.assertEqual(r.returncode, 0, r.stderr)
        order = re.findall(r"^run (\d) \[/.*/(fast|slow)/slamd\]", r.stdout, re.M)
        self.assertEqual(order, [("1", "fast"), ("1", "slow"), ("2", "fast"), ("2", "slow"), ("3", "fast"), ("3", "slow")])
        m = re.search(r"^against .*/slow/slamd: median CPU ([0-9.]+) s, \d+x real time; --bin's CPU is ([0-9.]+) of it$",
                      r.stdout, re.M)
        self.assertIsNotNone(m, r.stdout)
        self.assertLess(float(m.group(2)), 0.75, r.stdout)  # a third of the loop: well under the slow one
        self.assertGreater(float(m.group(2)), 0.1, r.stdout)


if __name__ == "__main__":
    try:
        unittest.main(argv=sys.argv[:1])
    finally:
        shutil.rmtree(STUBS)
