#!/usr/bin/env python3
"""One time base (docs/ros.md, "Time"): a live acquisition's samples, its run folder, its live
run.mcap and a re-export of the folder carry the same stamp for every sample, to the nanosecond,
on the bus (`hil echo pose_wrench` prints header.stamp); and that stamp is run.yaml's start_time
plus the sample's t, computed here in integer nanoseconds from the files' text. `hil replay --clock`
publishes the recording's own instants on /clock, and a replay publishes /tf as well.

Usage: test_time_base.py HIL SOURCE_DIR"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from datetime import datetime, timezone
from decimal import Decimal

HIL, SRC = sys.argv[1], sys.argv[2]
RUN = os.path.join(SRC, "examples", "runs", "press_slide")
RIG = os.path.join(SRC, "examples", "rigs", "press_bench.yaml")
ENV = dict(os.environ, HIL_DDS_DOMAIN=str(60 + os.getpid() % 20))  # 60-79: no other test uses them
STAMP = re.compile(r" stamp=(\d+)\.(\d{9})$")


def stamps(echo_stdout):
    out = []
    for line in echo_stdout.splitlines():
        m = STAMP.search(line)
        if m:
            out.append(int(m.group(1)) * 10**9 + int(m.group(2)))
    return out


def start_ns(run_yaml):
    """start_time: 2026-11-28T10:00:00.123456789Z -> ns since the epoch, without floating point."""
    with open(run_yaml) as f:
        text = f.read()
    m = re.search(r"start_time: (\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d)(?:\.(\d{1,9}))?Z", text)
    whole = datetime.strptime(m.group(1), "%Y-%m-%dT%H:%M:%S").replace(tzinfo=timezone.utc)
    frac = (m.group(2) or "").ljust(9, "0")
    return int(whole.timestamp()) * 10**9 + int(frac)


def t_column(samples_csv):
    with open(samples_csv) as f:
        lines = [l for l in f.read().splitlines() if l and not l.startswith("#")]
    return [Decimal(l.split(",")[0]) for l in lines[1:]]


def replay_and_echo(source, *extra, count, speed="0"):
    """Replays `source` to one `hil echo pose_wrench -n count` and returns what it printed."""
    echo = subprocess.Popen([HIL, "echo", "pose_wrench", "--timeout", "60", "-n", str(count)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=ENV)
    r = subprocess.run([HIL, "replay", source, "--speed", speed, "--wait-subscribers", "1", *extra], capture_output=True, text=True,
                       timeout=120, env=ENV)
    assert r.returncode == 0, r.stderr
    out, err = echo.communicate(timeout=90)
    assert echo.returncode == 0, err
    return out, r.stderr


class TimeBase(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp()
        cls.run_dir = os.path.join(cls.work, "run")
        # The live stamps: everything acquire publishes, from before its first sample (SIGINT ends echo).
        echo = subprocess.Popen([HIL, "echo", "pose_wrench"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
        r = subprocess.run([HIL, "acquire", "--rig", RIG, "--out", cls.run_dir, "--play", RUN, "--play-speed", "4", "--mcap",
                            "--wait-subscribers", "1"], capture_output=True, text=True, timeout=120, env=ENV)
        time.sleep(0.5)
        echo.send_signal(signal.SIGINT)
        out, _ = echo.communicate(timeout=30)
        assert r.returncode == 0, r.stderr
        cls.live = stamps(out)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work)

    def test_every_path_stamps_every_sample_alike(self):
        rows = len(t_column(os.path.join(self.run_dir, "samples.csv")))
        self.assertGreater(rows, 50)
        self.assertEqual(len(self.live), rows, "the live bus lost or added samples")
        # The rule, from the files' text: start_time + t, in integer ns.
        start = start_ns(os.path.join(self.run_dir, "run.yaml"))
        rule = [start + int((t * 10**9).to_integral_value()) for t in t_column(os.path.join(self.run_dir, "samples.csv"))]
        self.assertEqual(self.live, rule, "live stamps differ from run.yaml's start_time + samples.csv's t")

        folder, _ = replay_and_echo(self.run_dir, count=rows)
        live_mcap, _ = replay_and_echo(os.path.join(self.run_dir, "run.mcap"), count=rows)
        export = os.path.join(self.work, "export.mcap")
        r = subprocess.run([HIL, "export", self.run_dir, "--mcap", export], capture_output=True, text=True, env=ENV)
        self.assertEqual(r.returncode, 0, r.stderr)
        exported, _ = replay_and_echo(export, count=rows)
        self.assertEqual(stamps(folder), self.live, "hil replay RUN")
        self.assertEqual(stamps(live_mcap), self.live, "hil replay RUN/run.mcap (recorded live)")
        self.assertEqual(stamps(exported), self.live, "hil replay of hil export RUN")

    def test_clock_carries_the_recordings_instants(self):
        # The shipped run (6.5 s) in real time: /clock is best effort with a depth of 1 (ROS 2's
        # ClockQoS) and the echo's reader may be discovered only at the next announcement, so it
        # takes 20 ticks of the 650 or so instants.
        clock = subprocess.Popen([HIL, "echo", "clock", "--timeout", "30", "-n", "20"], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, env=ENV)
        rows = len(t_column(os.path.join(RUN, "samples.csv")))
        _, replayed = replay_and_echo(RUN, "--clock", speed="1", count=rows)
        c_out, c_err = clock.communicate(timeout=60)
        self.assertEqual(clock.returncode, 0, c_err + replayed)
        ticks = [int(s) * 10**9 + int(ns) for s, ns in (l.split(".") for l in c_out.split())]
        self.assertEqual(len(ticks), 20)
        self.assertEqual(ticks, sorted(ticks), "/clock went backwards")
        # The recording's instants only: /tf_static at the run's start and the samples' stamps.
        start = start_ns(os.path.join(RUN, "run.yaml"))
        instants = {start} | {start + int((t * 10**9).to_integral_value()) for t in t_column(os.path.join(RUN, "samples.csv"))}
        self.assertEqual([t for t in ticks if t not in instants], [], "/clock ticks that are no instant of the recording")

    def test_a_replay_publishes_the_moving_frame_too(self):
        tf = subprocess.Popen([HIL, "echo", "tf", "-n", "10", "--timeout", "30"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True, env=ENV)
        rows = len(t_column(os.path.join(RUN, "samples.csv")))
        _, replayed = replay_and_echo(RUN, speed="1", count=rows)  # 6.5 s: time to discover the echo
        out, err = tf.communicate(timeout=60)
        self.assertEqual(tf.returncode, 0, err + replayed)
        self.assertEqual(out.count("robot_base -> ee"), 10, out)

    def test_echo_prints_exactly_its_count(self):
        # A replay as fast as it can go delivers many samples between two of echo's checks of its
        # count: it must still print exactly --count, the recording's first ones, and exit 0.
        out, _ = replay_and_echo(RUN, count=3)
        start = start_ns(os.path.join(RUN, "run.yaml"))
        first = [start + int((t * 10**9).to_integral_value()) for t in t_column(os.path.join(RUN, "samples.csv"))[:3]]
        self.assertEqual(stamps(out), first, out)
        self.assertEqual(len(out.splitlines()), 3, out)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
