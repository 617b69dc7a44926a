#!/usr/bin/env python3
"""Tests of the whiskeye Python package (docs/python.md), as built in the build tree.

  test_whiskeye_package.py unit        --build BUILD --source SRC
  test_whiskeye_package.py integration --build BUILD --source SRC

unit: the log reader on logs written here (round trip of every generated type with the standard
library only, a truncated last event, garbage between events, strict mode), and channels.py against
channels.h and docs/lcm-channels.md's table.
integration: a short vita-sim -> slamd --replay run read by the package: per-channel counts equal
whiskeye-logcheck's, every stack channel decodes, a few field values agree with vita-eval's JSON,
a cut-off copy of the log stops cleanly and says so, and examples/plot_run.py writes a PNG headless.
"""
import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import unittest
import warnings

ARGS = None


def write_log(path, events):
    """An LCM log of (timestamp, channel, data) events, as lcm-logger writes them."""
    with open(path, "wb") as f:
        for n, (t, channel, data) in enumerate(events):
            c = channel.encode()
            f.write(struct.pack(">Iqqii", 0xEDA1DA01, n, t, len(c), len(data)) + c + data)


def import_package():
    """Imports the package as built (build/python) as the global `whiskeye`."""
    sys.path.insert(0, os.path.join(ARGS.build, "python"))
    global whiskeye
    import whiskeye  # noqa: F401
    import whiskeye.log  # noqa: F401


class Unit(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import_package()
        cls.tmp = tempfile.TemporaryDirectory()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def sample_events(self):
        pose = whiskeye.vita_pose_t()
        pose.utime, pose.x, pose.y, pose.theta, pose.experience_id, pose.mode = 10, 1.5, -2.0, 0.25, 3, 2
        m = whiskeye.vita_map_t()
        e = whiskeye.experience_t()
        e.id, e.x, e.y, e.dense = 7, 0.5, 0.25, True
        link = whiskeye.link_t()
        link.from_id, link.to_id = 7, 7
        m.experiences, m.num_experiences, m.links, m.num_links, m.mode = [e], 1, [link], 1, 1
        return [(1_000_000 + i, whiskeye.channels.VITA_POSE if i % 2 == 0 else whiskeye.channels.VITA_MAP,
                 (pose if i % 2 == 0 else m).encode()) for i in range(10)]

    def test_imports_only_the_standard_library(self):
        # Debian 12 has no python3-lcm: the package must not need the `lcm` module.
        code = ("import sys; sys.modules['lcm'] = None; sys.path.insert(0, %r); import whiskeye, whiskeye.log; "
                "print(whiskeye.log.SYNC)" % os.path.join(ARGS.build, "python"))
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_reads_and_decodes_every_event_of_a_whole_log(self):
        write_log(self.path("whole.lcmlog"), self.sample_events())
        reader = whiskeye.log.read(self.path("whole.lcmlog"))
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # an undamaged log warns of nothing
            events = list(reader)
        self.assertEqual(len(events), 10)
        self.assertFalse(reader.damage)
        self.assertEqual(str(reader.damage), "")
        self.assertEqual([e.eventnum for e in events], list(range(10)))
        self.assertEqual(events[3].timestamp, 1_000_003)
        pose = events[0].decode()
        self.assertIsInstance(pose, whiskeye.vita_pose_t)
        self.assertEqual((pose.x, pose.y, pose.experience_id), (1.5, -2.0, 3))
        m = events[1].decode()
        self.assertEqual(m.experiences[0].id, 7)
        self.assertTrue(m.experiences[0].dense)

    def test_a_truncated_last_event_stops_cleanly_and_says_so(self):
        write_log(self.path("whole.lcmlog"), self.sample_events())
        data = open(self.path("whole.lcmlog"), "rb").read()
        open(self.path("cut.lcmlog"), "wb").write(data[:-7])
        reader = whiskeye.log.read(self.path("cut.lcmlog"))
        with self.assertWarns(whiskeye.log.LogDamageWarning) as w:
            events = list(reader)
        self.assertEqual(len(events), 9)
        self.assertTrue(reader.damage.truncated_tail)
        self.assertIn("truncated LCM log: the event at byte", str(reader.damage))
        self.assertIn("the last event cut off", str(w.warning))
        with self.assertRaisesRegex(whiskeye.log.LogError, "cut.lcmlog: truncated LCM log"):
            list(whiskeye.log.read(self.path("cut.lcmlog"), strict=True))

    def test_garbage_between_events_is_skipped_by_resynchronising(self):
        write_log(self.path("whole.lcmlog"), self.sample_events())
        data = open(self.path("whole.lcmlog"), "rb").read()
        at = data.find(struct.pack(">I", 0xEDA1DA01), len(data) // 2)
        open(self.path("junk.lcmlog"), "wb").write(data[:at] + b"JUNK!JUNK!" + data[at:])
        reader = whiskeye.log.read(self.path("junk.lcmlog"))
        with self.assertWarns(whiskeye.log.LogDamageWarning):
            events = list(reader)
        self.assertEqual(len(events), 10, "every event around the garbage is read")
        self.assertEqual(reader.damage.skipped_bytes, 10)
        self.assertEqual(reader.damage.places, 1)
        self.assertIn("corrupt LCM log: no event sync word at byte %d" % at, str(reader.damage))

    def test_what_is_no_log_file_is_refused_as_the_cxx_reader_refuses_it_without_waiting(self):
        fifo = self.path("fifo.lcmlog")
        os.mkfifo(fifo)
        for path, says in [(fifo, "not a regular file"), ("/dev/zero", "not a regular file"),
                           (self.tmp.name, "not a regular file"),
                           ("/proc/self/status", "not a regular file (it reports 0 bytes but holds data)")]:
            # In a child: a reader that waits for the FIFO's writer is a failure, not a hung test.
            code = ("import sys; sys.path.insert(0, %r); import whiskeye.log\n"
                    "try:\n    print(sum(1 for _ in whiskeye.log.read(%r)))\n"
                    "except whiskeye.log.LogError as e:\n    print(e)" % (os.path.join(ARGS.build, "python"), path))
            try:
                r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=20)
            except subprocess.TimeoutExpired:
                self.fail("%s: the reader waits (for a writer)" % path)
            self.assertEqual(r.stdout.strip(), "%s: cannot open the LCM log for reading: %s" % (path, says), r.stderr)

    def test_the_source_trees_package_reads_a_log_and_says_where_the_types_are(self):
        write_log(self.path("whole.lcmlog"), self.sample_events())
        code = ("import sys; sys.path.insert(0, %r); import whiskeye.log\n"
                "events = list(whiskeye.log.read(%r)); print(len(events), events[0].channel)\n"
                "try:\n    events[0].decode()\nexcept ImportError as e:\n    print(e)"
                % (os.path.abspath(os.path.join(ARGS.source, "python")), self.path("whole.lcmlog")))
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=self.tmp.name)
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertEqual(lines[0], "10 VITA_POSE")
        self.assertIn("whiskeye.vita_pose_t: the LCM types are generated at build time", lines[1])

    def test_the_checked_in_channels_module_is_the_one_the_build_generates(self):
        with open(os.path.join(ARGS.source, "python/whiskeye/channels.py")) as f:
            checked_in = f.read()
        with open(os.path.join(ARGS.build, "python/whiskeye/channels.py")) as f:
            generated = f.read()
        self.assertEqual(checked_in, generated, "python/whiskeye/channels.py is out of date with channels.h: "
                         "copy build/python/whiskeye/channels.py over it")

    def test_garbage_of_sync_words_is_skipped_to_the_next_event(self):
        write_log(self.path("whole.lcmlog"), self.sample_events())
        data = open(self.path("whole.lcmlog"), "rb").read()
        at = data.find(struct.pack(">I", 0xEDA1DA01), len(data) // 2)
        # Every 4 bytes a candidate, each failing; a header's worth of zeros so none reads the next one.
        garbage = struct.pack(">I", 0xEDA1DA01) * 16384 + bytes(28)
        open(self.path("sync.lcmlog"), "wb").write(data[:at] + garbage + data[at:])
        reader = whiskeye.log.read(self.path("sync.lcmlog"))
        with self.assertWarns(whiskeye.log.LogDamageWarning):
            events = list(reader)
        self.assertEqual(len(events), 10)
        self.assertEqual((reader.damage.skipped_bytes, reader.damage.places), (len(garbage), 1))

    def test_decoding_says_what_is_wrong(self):
        pose = whiskeye.vita_pose_t().encode()
        write_log(self.path("odd.lcmlog"), [(1, "NOT_OURS", pose), (2, "VITA_MAP", pose), (3, "VITA_POSE", pose[:-3])])
        odd, wrong, short = list(whiskeye.log.read(self.path("odd.lcmlog")))
        with self.assertRaises(whiskeye.log.UnknownChannelError):
            odd.decode()
        with self.assertRaisesRegex(whiskeye.log.DecodeError, "VITA_MAP at byte .*: not a vita_map_t"):
            wrong.decode()
        with self.assertRaises(whiskeye.log.DecodeError):
            short.decode()

    def test_channels_agree_with_channels_h_and_the_channel_reference(self):
        with open(os.path.join(ARGS.source, "common/include/whiskeye/common/channels.h")) as f:
            header = f.read()
        names = dict(re.findall(r'inline constexpr const char\* (k\w+) = "(\w+)";', header))
        self.assertEqual(set(whiskeye.channels.TYPES), set(names.values()))
        with open(os.path.join(ARGS.source, "docs/lcm-channels.md")) as f:
            table = dict(re.findall(r"^\| `([A-Z_]+)` \| `(\w+)` \|", f.read(), re.M))
        self.assertEqual(whiskeye.channels.TYPES, table, "docs/lcm-channels.md's table and channels.h disagree")
        for channel, type_name in whiskeye.channels.TYPES.items():
            cls = whiskeye.log.type_for_channel(channel)
            self.assertEqual(cls.__name__, type_name)
            msg = cls()
            if type_name == "image_t":
                msg.data = b""  # lcm-gen 1.3.1 defaults a byte array to "" (Python 2's bytes): docs/python.md
            self.assertIsInstance(cls.decode(msg.encode()), cls)  # every type round-trips, stdlib only


class Integration(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import_package()
        cls.tmp = tempfile.TemporaryDirectory()
        bin_dir, src = os.path.join(ARGS.build, "bin"), ARGS.source
        cls.sim = os.path.join(cls.tmp.name, "sim.lcmlog")
        cls.slam = os.path.join(cls.tmp.name, "slam.lcmlog")
        cls.sh([os.path.join(bin_dir, "vita-sim"), "--world", src + "/config/worlds/aliased_arena.yaml", "--robot",
                 src + "/config/robot.yaml", "--duration", "12", "--seed", "4", "--quiet", "--output", cls.sim])
        cls.sh([os.path.join(bin_dir, "slamd"), "--replay", cls.sim, "--output", cls.slam, "--mode", "vita",
                 "--config", src + "/config/slam.yaml", "--robot", src + "/config/robot.yaml"])
        cls.logcheck = {}
        for log in (cls.sim, cls.slam):
            out = cls.sh([os.path.join(bin_dir, "whiskeye-logcheck"), log], ok=(0, 1)).stdout
            cls.logcheck[log] = {m.group(1): int(m.group(2)) for m in re.finditer(r"^([A-Z_]+)\s+(\d+)\b", out, re.M)}
        cls.metrics = os.path.join(cls.tmp.name, "metrics.json")
        cls.sh([os.path.join(bin_dir, "vita-eval"), "--input", cls.slam, "--json", cls.metrics])

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @staticmethod
    def sh(cmd, ok=(0,), env=None):
        r = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if r.returncode not in ok:
            raise AssertionError("%s exited %d:\n%s%s" % (" ".join(cmd), r.returncode, r.stdout, r.stderr))
        return r

    def counts(self, log):
        out = {}
        for e in whiskeye.log.read(log):
            out[e.channel] = out.get(e.channel, 0) + 1
        return out

    def test_counts_per_channel_equal_whiskeye_logchecks(self):
        for log in (self.sim, self.slam):
            expected = self.logcheck[log]
            self.assertGreaterEqual(len(expected), 5, "whiskeye-logcheck's table was not parsed")
            self.assertEqual(self.counts(log), expected, log)

    def test_every_stack_channel_decodes_and_fields_agree_with_vita_eval(self):
        decoded = {}
        last_map, poses, gt = None, 0, 0
        for e in whiskeye.log.read(self.slam):
            if e.channel not in whiskeye.channels.TYPES:
                continue
            m = e.decode()
            decoded[e.channel] = decoded.get(e.channel, 0) + 1
            if e.channel == whiskeye.channels.VITA_MAP:
                last_map = m
            elif e.channel == whiskeye.channels.VITA_POSE:
                poses += 1
                self.assertEqual(m.mode, whiskeye.vita_pose_t.MODE_VITA)
            elif e.channel == whiskeye.channels.GROUND_TRUTH:
                gt += 1
        for channel in ("VITA_POSE", "VITA_EVENT", "VITA_MATCH", "VITA_MAP", "GROUND_TRUTH"):
            self.assertGreater(decoded.get(channel, 0), 0, channel)
        for e in whiskeye.log.read(self.sim):  # the simulator's channels, one of each
            if e.channel in whiskeye.channels.TYPES:
                e.decode()
        with open(self.metrics) as f:
            run = json.load(f)["runs"][0]
        self.assertEqual(run["mode"], "vita")
        self.assertEqual(run["counts"]["pose_samples"], poses)
        self.assertEqual(run["counts"]["ground_truth_samples"], gt)
        self.assertEqual(run["counts"]["map_experiences"], len(last_map.experiences))
        self.assertEqual(run["counts"]["map_links"], last_map.num_links)
        self.assertEqual(last_map.mode, whiskeye.vita_pose_t.MODE_VITA)

    def test_a_log_cut_off_mid_event_is_read_to_the_cut(self):
        data = open(self.slam, "rb").read()
        cut = os.path.join(self.tmp.name, "cut.lcmlog")
        open(cut, "wb").write(data[: len(data) - 100])
        whole = sum(1 for _ in whiskeye.log.read(self.slam))
        reader = whiskeye.log.read(cut)
        with self.assertWarns(whiskeye.log.LogDamageWarning):
            n = sum(1 for _ in reader)
        self.assertEqual(n, whole - 1)
        self.assertTrue(reader.damage.truncated_tail)

    def test_the_example_plots_a_run_headless(self):
        png = os.path.join(self.tmp.name, "run.png")
        env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.path.join(ARGS.build, "python"),
                   PYTHONDONTWRITEBYTECODE="1")
        env.pop("DISPLAY", None)
        r = self.sh([sys.executable, os.path.join(ARGS.source, "python/examples/plot_run.py"), self.slam,
                      "--output", png], env=env)
        self.assertIn("wrote " + png, r.stdout)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertGreater(os.path.getsize(png), 20_000)


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("suite", choices=["unit", "integration"])
    parser.add_argument("--build", required=True)
    parser.add_argument("--source", required=True)
    ARGS, rest = parser.parse_known_args()
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(Unit if ARGS.suite == "unit" else Integration)
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    sys.exit(0 if result.wasSuccessful() and not result.skipped else 1)


if __name__ == "__main__":
    main()
