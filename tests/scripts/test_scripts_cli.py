#!/usr/bin/env python3
"""Every script of scripts/ has a correct --help (exit 0, its own usage line) and turns a bad command
line into one line "<script>: <reason>" and exit 2, before it builds, installs or runs anything."""
import os
import subprocess
import sys
import unittest

SCRIPTS = os.path.join(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "../.."),
                       "scripts")

# Per script: bad command lines (each must fail at once). lcm-spy passes what it does not know to
# lcm-spy itself, so only its --help is ours.
BAD = {
    "demo": [["--bogus"], ["--seed"], ["--seed", "2", "--laps"]],
    "seeds": [["--bogus"], ["--world"]],
    "fuzz": [["--bogus"], ["--minutes"], ["--seconds", "x"], ["no_such_target"]],
    "suite": [["--bogus"], ["--worlds"], ["--worlds", "x"]],
    "install-deps": [["--bogus"]],
    "netns-run": [[]],
    "test": [["--no-such-stage"]],
    "lcm-spy": [],
    "bench": [["--bogus"], ["--filter"], ["--repetitions", "x"], ["--only", "no-such-bench"]],
    "replay-speed": [["--bogus"], ["--runs", "0"], ["--mode", "x"], ["--log", "/no/such/log"]],
}


def run(name, args):
    return subprocess.run([os.path.join(SCRIPTS, name)] + args, capture_output=True, text=True, timeout=60,
                          stdin=subprocess.DEVNULL)


class Scripts(unittest.TestCase):
    def test_every_script_is_covered(self):
        self.assertEqual(sorted(os.listdir(SCRIPTS)), sorted(BAD))

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


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
