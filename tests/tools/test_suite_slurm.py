#!/usr/bin/python3
"""scripts/suite --executor slurm on a real single-node Slurm cluster started here (slurm_cluster.py):
a quick suite through sbatch gives the local executor's numbers; a failing array task is listed with
its log and rerun alone (--retry-failed); a finished world is not resubmitted; a partition that does
not exist and jobs that do not end in --timeout are one-line errors. No daemon outlives the test.

  test_suite_slurm.py SOURCE_DIR BIN_DIR
"""
import json
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from slurm_cluster import SlurmCluster  # noqa: E402

SOURCE, BIN = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
SUITE = os.path.join(SOURCE, "scripts", "suite")
cluster = None


def setUpModule():
    global cluster
    cluster = SlurmCluster().__enter__()


def tearDownModule():
    cluster.__exit__(None, None, None)
    assert not cluster.leftovers(), f"processes of the test cluster left behind: {cluster.leftovers()}"
    assert not cluster.new_daemons(), f"munged/Slurm daemons left behind: {cluster.new_daemons()}"


def suite(*args, env=None, timeout=600):
    return subprocess.run([SUITE, *args], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          env=env or cluster.env(), timeout=timeout)


def read(path):
    with open(path) as f:
        return f.read()


def load(folder):
    with open(os.path.join(folder, "suite.json")) as f:
        return json.load(f)


def metrics(doc):
    return {w["index"]: w["modes"] for w in doc["worlds"]}


def our_jobs():
    return subprocess.run(["squeue", "--noheader", "--format=%i %T"], capture_output=True, text=True,
                          env=cluster.env(), timeout=30).stdout.split()


class SlurmSuite(unittest.TestCase):
    """One quick suite (3 worlds, 1 lap) locally, then through Slurm with world 2 failing, then
    --retry-failed with it fixed, then once more with every world done."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="suite_slurm_test_")
        cls.addClassCleanup(shutil.rmtree, cls.tmp)
        cls.local = suite("--quick", "--bin", BIN, "--results", os.path.join(cls.tmp, "local"), "--no-plots")
        # vita-sim fails on world 2 (seed 1002) while the marker exists: the programs (and so the
        # worlds' key) stay the same when it is removed.
        bins = os.path.join(cls.tmp, "bin")
        os.makedirs(bins)
        for tool in ("slamd", "vita-eval"):
            os.symlink(os.path.join(BIN, tool), os.path.join(bins, tool))
        cls.marker = os.path.join(cls.tmp, "break-world-2")
        open(cls.marker, "w").close()
        with open(os.path.join(bins, "vita-sim"), "w") as f:
            f.write(f"#!/bin/sh\ncase \" $* \" in *\" 1002 \"*) if [ -e {cls.marker} ]; then\n"
                    f"  echo 'vita-sim: broken on purpose' >&2; exit 3; fi ;; esac\n"
                    f"exec {os.path.join(BIN, 'vita-sim')} \"$@\"\n")
        os.chmod(os.path.join(bins, "vita-sim"), stat.S_IRWXU)
        cls.results = os.path.join(cls.tmp, "slurm")
        args = ("--quick", "--executor", "slurm", "--partition", cluster.partition, "--bin", bins,
                "--results", cls.results, "--timeout", "600")
        cls.broken = suite(*args)
        cls.broken_doc = load(cls.results) if os.path.exists(os.path.join(cls.results, "suite.json")) else None
        cls.broken_log = read(os.path.join(cls.results, "world-002", "run.log"))
        cls.broken_task = read(os.path.join(cls.results, "world-002", "slurm.out"))
        os.remove(cls.marker)
        cls.retried = suite(*args, "--retry-failed")
        cls.retried_doc = load(cls.results)
        cls.retried_md = read(os.path.join(cls.results, "suite.md"))
        cls.again = suite(*args)
        # A parameter study on Slurm: a sweep of two values, each world simulated once in its task.
        cls.study_dir = os.path.join(cls.tmp, "study")
        study = ("--quick", "--executor", "slurm", "--partition", cluster.partition, "--bin", BIN, "--results",
                 cls.study_dir, "--timeout", "600", "--no-plots", "--sweep", "slam.match.threshold_visual=0.1,0.3")
        cls.study = suite(*study)
        cls.study_doc = json.loads(read(os.path.join(cls.study_dir, "study.json"))) \
            if os.path.exists(os.path.join(cls.study_dir, "study.json")) else None
        cls.study_again = suite(*study)

    def test_the_local_run_ran(self):
        self.assertEqual(self.local.returncode, 0, self.local.stderr)

    def test_a_failing_array_task_is_listed_with_its_log_and_fails_the_run(self):
        self.assertEqual(self.broken.returncode, 1, self.broken.stderr)
        log = os.path.join(self.results, "world-002", "run.log")
        self.assertIn(f"world 2 (seed 1002) FAILED: vita-sim exited 3 (see {log})", self.broken.stderr)
        self.assertIn("vita-sim: broken on purpose", self.broken_log)
        self.assertIn(f"suite: 1 world(s) failed: 2 ({log})", self.broken.stderr)
        self.assertIn("--retry-failed", self.broken.stderr.splitlines()[-1])
        # The array task itself failed, and said so in its Slurm output.
        self.assertIn("suite: world 2 FAILED: vita-sim exited 3", self.broken_task)
        # The aggregation job still wrote the summary of the two others, and named the failure.
        self.assertIsNotNone(self.broken_doc)
        self.assertEqual([w["index"] for w in self.broken_doc["worlds"]], [1, 3])
        self.assertEqual([f["index"] for f in self.broken_doc["failed_worlds"]], [2])
        self.assertEqual(self.broken_doc["executor"], "slurm")
        self.assertEqual(self.broken.stderr.count("] world "), 3, self.broken.stderr)

    def test_retry_failed_submits_only_the_failed_world(self):
        self.assertEqual(self.retried.returncode, 0, self.retried.stderr)
        self.assertIn("1 world(s) as Slurm array job", self.retried.stderr)
        self.assertIn("(2), aggregation job", self.retried.stderr)
        self.assertEqual(self.retried.stderr.count(" resumed: "), 2, self.retried.stderr)
        self.assertEqual(self.retried_doc["failed_worlds"], [])
        self.assertFalse(os.path.exists(os.path.join(self.results, "world-002", "failed.json")))

    def test_slurm_gives_the_local_executors_numbers(self):
        local = load(os.path.join(self.tmp, "local"))
        self.assertEqual([w["world_seed"] for w in self.retried_doc["worlds"]], [1001, 1002, 1003])
        self.assertEqual(metrics(self.retried_doc), metrics(local))
        self.assertEqual(self.retried_doc["summary"], local["summary"])
        self.assertEqual(self.retried_doc["fooled"], local["fooled"])
        for w in self.retried_doc["worlds"]:
            self.assertEqual(w["generation"], next(x for x in local["worlds"] if x["index"] == w["index"])["generation"])

    def test_the_aggregation_job_writes_the_summary_and_plots(self):
        md = self.retried_md
        self.assertIn("| vita | ATE RMSE (m) |", md)
        self.assertIn(f"as Slurm array job {self.retried_doc['slurm']['array_job']}", md)
        for png in ("metrics_by_mode.png", "arr_vs_arcr.png"):
            self.assertGreater(os.path.getsize(os.path.join(self.results, "plots", png)), 1000, png)
        self.assertIn("suite: ", read(os.path.join(self.results, "slurm-aggregate.out")))
        # The simulator logs went to the task's scratch, not to the shared results.
        left = [f for _, _, files in os.walk(self.results) for f in files if f.endswith(".lcmlog")]
        self.assertEqual(left, [])

    def test_a_finished_world_is_not_resubmitted(self):
        self.assertEqual(self.again.returncode, 0, self.again.stderr)
        self.assertNotIn("Slurm array job", self.again.stderr)
        self.assertEqual(self.again.stderr.count(" resumed: "), 3, self.again.stderr)
        self.assertEqual(metrics(load(self.results)), metrics(self.retried_doc))

    def test_a_study_runs_each_world_once_as_a_task_and_the_aggregation_compares_the_configs(self):
        self.assertEqual(self.study.returncode, 0, self.study.stderr)
        self.assertIn("3 world(s) as Slurm array job", self.study.stderr)
        self.assertIsNotNone(self.study_doc)
        self.assertIsNotNone(self.study_doc["slurm"]["aggregate_job"])
        labels = [c["label"] for c in self.study_doc["configs"]]
        self.assertEqual(labels, ["threshold_visual=0.1", "threshold_visual=0.3"])
        self.assertEqual(self.study.stderr.count("] (seed"), 6, self.study.stderr)
        local = load(os.path.join(self.tmp, "local"))
        self.assertEqual({w["index"]: w["configs"][labels[0]] for w in self.study_doc["worlds"]}, metrics(local))
        for i in (1, 2, 3):
            log = read(os.path.join(self.study_dir, f"world-{i:03d}", "run.log"))
            self.assertEqual(log.count("vita-sim --world "), 1, log)
            self.assertEqual(log.count("slamd --replay"), 6, log)
        self.assertIn("## Side by side", read(os.path.join(self.study_dir, "study.md")))
        # Resumable: every (world, value) pair is done, nothing is submitted.
        self.assertEqual(self.study_again.returncode, 0, self.study_again.stderr)
        self.assertNotIn("Slurm array job", self.study_again.stderr)
        self.assertEqual(self.study_again.stderr.count(" resumed: "), 6, self.study_again.stderr)


class SlurmBadInput(unittest.TestCase):
    def one_line_error(self, r, text):
        lines = r.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertIn(text, lines[0])

    def test_a_partition_that_does_not_exist_is_one_line_and_nothing_queued(self):
        with tempfile.TemporaryDirectory() as d:
            r = suite("--quick", "--executor", "slurm", "--partition", "nosuchpartition", "--bin", BIN,
                      "--results", d)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn("suite: sbatch --partition nosuchpartition: ", r.stderr)
            self.assertIn("Invalid partition name specified", r.stderr.strip().splitlines()[-1])
            self.assertFalse(os.path.exists(os.path.join(d, "world-001", "failed.json")))
        self.assertEqual(our_jobs(), [])

    def test_jobs_that_do_not_end_in_the_timeout_are_cancelled(self):
        with tempfile.TemporaryDirectory() as d:
            # Not eligible to start for an hour: without the timeout this would wait.
            r = suite("--worlds", "1", "--laps", "1", "--executor", "slurm", "--bin", BIN, "--results", d,
                      "--sbatch-args=--begin=now+3600", "--timeout", "3", timeout=120)
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertIn("did not end in 3 s (--timeout): cancelled", r.stderr.strip().splitlines()[-1])
        self.assertEqual(our_jobs(), [])

    def test_no_sbatch_on_the_path_is_one_line(self):
        env = dict(cluster.env(), PATH="/nonexistent")
        with tempfile.TemporaryDirectory() as d:
            r = suite("--quick", "--executor", "slurm", "--bin", BIN, "--results", d, env=env)
        self.assertEqual(r.returncode, 2)
        self.one_line_error(r, "suite: --executor slurm: sbatch is not on the PATH")


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
