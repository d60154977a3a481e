#!/usr/bin/env python3
"""Runs the real `hil` binary: help, version, validate on the shipped examples, and a bad input
of every kind through the command line (non-zero exit, message naming file, line and field)."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
EXAMPLE_RUN = os.path.join(SRC, "examples", "runs", "press_slide")
EXAMPLE_RIG = os.path.join(SRC, "examples", "rigs", "press_bench.yaml")


# Sanitizer builds run 2-3x slower (docs/sanitizers.md): their test presets set this factor.
TIME_SCALE = float(os.environ.get("HIL_TEST_TIME_SCALE", "1"))


def hil(*args, env=None, text=True):
    """`hil ARGS` on this test process's own DDS domain. text=False keeps stdout and stderr as bytes
    (Python's universal newlines would turn a carriage return into a newline)."""
    e = dict(os.environ)
    e["HIL_DDS_DOMAIN"] = str(150 + os.getpid() % 50)
    if env:
        e.update(env)
    return subprocess.run([HIL, *args], capture_output=True, text=text, timeout=120 * TIME_SCALE, env=e)


class Cli(unittest.TestCase):
    def test_help_and_version(self):
        r = hil("--help")
        self.assertEqual(r.returncode, 0)
        for cmd in ("validate", "demo"):
            self.assertIn(cmd, r.stdout)
        r = hil("validate", "--help")
        self.assertEqual(r.returncode, 0)
        self.assertIn("PATH", r.stdout)
        r = hil("--version")
        self.assertEqual(r.returncode, 0)
        self.assertRegex(r.stdout, r"hil \d+\.\d+\.\d+")

    def usage_error(self, args, *needles, hint="hil"):
        """Exit 2, 'error: ...' naming the bad word, a hint to the command's --help, nothing on stdout."""
        r = hil(*args)
        self.assertEqual(r.returncode, 2, (args, r.stdout, r.stderr))
        self.assertEqual(r.stdout, "", args)
        first, second = (r.stderr.splitlines() + ["", ""])[:2]
        self.assertTrue(first.startswith("error: "), r.stderr)
        for n in needles:
            self.assertIn(n, first, args)
        self.assertEqual(second, "run '%s --help' for the usage" % hint)
        return first

    def test_usage_errors_exit_2_naming_the_word(self):
        self.usage_error(["frobnicate"], "unknown command 'frobnicate'")
        self.assertNotIn("did you mean", self.usage_error(["frobnicate"]))
        self.usage_error(["diagnoze", "x"], "unknown command 'diagnoze'", "did you mean 'diagnose'")
        self.usage_error(["stiffness", "identfy"], "unknown command 'identfy'", "'hil stiffness'",
                         "did you mean 'identify'", hint="hil stiffness")
        self.usage_error([], "needs a command", "validate")
        self.usage_error(["contact"], "'hil contact' needs a command", "identify", hint="hil contact")
        self.usage_error(["validate", EXAMPLE_RUN, "--jsn"], "unknown option '--jsn'", "did you mean '--json'",
                         hint="hil validate")
        self.usage_error(["--frob", "validate", EXAMPLE_RUN], "unknown option '--frob'")
        self.usage_error(["validate"], "PATH is required", hint="hil validate")
        self.usage_error(["validate", EXAMPLE_RUN, "extra"], "unexpected argument 'extra'", hint="hil validate")
        self.usage_error(["stiffness", "identify", "t.csv"], "--rig is required", hint="hil stiffness identify")
        self.usage_error(["diagnose", EXAMPLE_RUN, "--rig"], "--rig", hint="hil diagnose")
        self.usage_error(["diagnose", EXAMPLE_RUN, "--folds", "1"], "--folds", "1", hint="hil diagnose")
        self.usage_error(["diagnose", EXAMPLE_RUN, "--folds", "many"], "--folds", "many", hint="hil diagnose")
        self.usage_error(["--log-level", "loud", "validate", EXAMPLE_RUN], "--log-level", "loud", hint="hil validate")
        self.usage_error(["contact", "identify", EXAMPLE_RUN, "--solver", "newton"], "--solver", "newton",
                         hint="hil contact identify")
        self.usage_error(["contact", "identify", EXAMPLE_RUN, "--geometric", "--lambda", "-1"], "--lambda", "'-1'",
                         hint="hil contact identify")
        # Help is not an error.
        for args in (["--help"], ["stiffness", "identify", "--help"]):
            r = hil(*args)
            self.assertEqual((r.returncode, r.stderr), (0, ""), args)
            self.assertIn("Usage:", r.stdout)

    def test_bad_input_after_parsing_exits_2_and_failures_1(self):
        r = hil("validate", os.path.join(tempfile.mkdtemp(), "none"))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("no such file", r.stderr)
        # A run folder that cannot be written is a failure, not bad input.
        r = hil("contact", "simulate", "--rig", EXAMPLE_RIG, "--trajectory",
                os.path.join(SRC, "examples", "trajectories", "press_slide.csv"), "--out", "/proc/hil-no-such/run")
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("/proc/hil-no-such/run", r.stderr)

    def test_demo_refuses_bad_options(self):
        # slow_slip is a candidate the generator cannot hide: refused as a usage error too.
        for args, field in ((("--decimate", "0"), "--decimate"), (("--effect", "magnetism"), "magnetism"),
                            (("--effect", "slow_slip"), "slow_slip")):
            r = hil("demo", *args, "--out", os.path.join(tempfile.mkdtemp(), "run"))
            self.assertEqual(r.returncode, 2, r.stdout + r.stderr)  # a usage error, before any work
            self.assertIn(field, r.stderr)

    def test_validate_examples(self):
        r = hil("validate", EXAMPLE_RUN)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("OK", r.stdout)
        self.assertRegex(r.stdout, r"rate 50\.00 Hz")
        self.assertIn("gaps: none", r.stdout)
        self.assertIn("polyhedra: 2", r.stdout)
        r = hil("validate", EXAMPLE_RIG)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("features: 2", r.stdout)
        self.assertIn("robot 'ur5e' (6 joints", r.stdout)


    def test_replay_and_echo_over_dds(self):
        env = dict(os.environ)
        env["HIL_DDS_DOMAIN"] = str(200 + os.getpid() % 30)
        with open(os.path.join(EXAMPLE_RUN, "samples.csv")) as f:
            rows = sum(1 for _ in f) - 1
        echo = subprocess.Popen([HIL, "echo", "pose_wrench", "-n", str(rows), "--timeout", "60"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        r = subprocess.run([HIL, "replay", EXAMPLE_RUN, "--speed", "0", "--wait-subscribers", "1"],
                           capture_output=True, text=True, timeout=120, env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        out, err = echo.communicate(timeout=60)
        self.assertEqual(echo.returncode, 0, err)
        lines = out.splitlines()
        self.assertEqual(len(lines), rows)
        self.assertTrue(lines[0].startswith("#0 t=0.0000"))
        self.assertTrue(lines[-1].startswith("#%d " % (rows - 1)))

    def test_echo_tf_static_and_diagnostics_of_an_acquisition(self):
        import time
        env = dict(os.environ)
        env["HIL_DDS_DOMAIN"] = str(44 + os.getpid() % 5)  # 44-48: no other test uses them
        out = tempfile.mkdtemp()
        acq = subprocess.Popen([HIL, "acquire", "--rig", EXAMPLE_RIG, "--out", os.path.join(out, "run"), "--play", EXAMPLE_RUN,
                                "--duration", "8"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        try:
            time.sleep(2.0)  # /tf_static was sent at start: the echo joins late and still gets it (latched)
            tf = subprocess.run([HIL, "echo", "tf_static", "-n", "1", "--timeout", "20"], capture_output=True, text=True,
                                timeout=60, env=env)
            diag = subprocess.run([HIL, "echo", "/diagnostics", "-n", "1", "--timeout", "20"], capture_output=True, text=True,
                                  timeout=60, env=env)
        finally:
            acq.communicate(timeout=60)
            shutil.rmtree(out)
        self.assertEqual(tf.returncode, 0, tf.stderr)
        self.assertIn("world -> force_plate", tf.stdout)
        self.assertIn("force_plate -> object2 p=[0 0 0.05]", tf.stdout)
        self.assertIn("world -> robot_base p=[-0.45 0 0]", tf.stdout)
        self.assertEqual(diag.returncode, 0, diag.stderr)
        self.assertRegex(diag.stdout, r"hil/force_plate (OK|WARN) ")
        self.assertIn("FT-FAKE1", diag.stdout)  # the plate's hardware id carries its serial

    def test_demo_runs_the_chain(self):
        out = tempfile.mkdtemp()
        # Another participant publishing samples on the demo's domain throughout (a slow replay): the
        # demo keeps to a partition of its own, so its bus count stays its own.
        env = dict(os.environ, HIL_DDS_DOMAIN=str(150 + os.getpid() % 50))
        # 6.5 s of samples at 1/50 of real time: 325 s, longer than the demo even on a loaded or sanitizer machine.
        intruder = subprocess.Popen([HIL, "replay", EXAMPLE_RUN, "--speed", str(0.02 / TIME_SCALE)], stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, env=env)
        try:
            raw = hil("demo", "--out", os.path.join(out, "run"), "--seed", "6", text=False)
            r = subprocess.CompletedProcess(raw.args, raw.returncode, raw.stdout.decode(), raw.stderr.decode())
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            self.assertRegex(r.stdout, r"\d+ ContactEstimate messages received")
            self.assertNotIn(" 0 ContactEstimate", r.stdout)
            self.assertIn("cause:           sensor_bias", r.stdout)
            self.assertIn("[6/6] the hidden effect was sensor_bias", r.stdout)
            self.assertIn("named by the diagnosis", r.stdout)
            self.assertRegex(r.stdout, r"on DDS domain \d+, partition hil-demo-\d+ \(watch: hil echo pose_wrench --dds-domain")
            self.assertIsNone(intruder.poll(), "the other publisher stopped before the demo ended: the test proves nothing")
            # stdout is a pipe here, as in a log file: plain progress lines, no carriage returns.
            self.assertNotIn(b"\r", raw.stdout)
            self.assertRegex(r.stdout, r"\n      \[1/\d+\] ")
            self.assertLess(max(len(line) for line in r.stdout.splitlines()), 300)
            self.assertTrue(os.path.exists(os.path.join(out, "run-diagnosis", "index.html")))
            self.assertEqual(hil("validate", os.path.join(out, "run")).returncode, 0)
            # The demo's run.mcap through the independent MCAP reader (tests/formats/mcap), when node is there.
            if os.environ.get("HIL_MCAP_CHECK"):
                run = os.path.join(out, "run")
                c = subprocess.run([os.environ["HIL_MCAP_NODE"], os.environ["HIL_MCAP_CHECK"], os.path.join(run, "run.mcap"),
                                    os.path.join(run, "samples.csv"), "--tf", "force_plate,receptacle_frame,acu_frame",
                                    "--min-status", "2", "--edge", "world,ee"], capture_output=True, text=True, timeout=120)
                self.assertEqual(c.returncode, 0, c.stdout + c.stderr)
        finally:
            intruder.kill()
            intruder.wait()
            shutil.rmtree(out)

    def test_acquire_play_loop_plays_the_run_again(self):
        # press_slide slides 20 mm in x over 6.48 s; at 4x with --play-loop and --duration 4 the rig
        # plays 16 s of it: the slide starts over twice (without the loop it would end after 1.6 s).
        import csv
        out = tempfile.mkdtemp()
        try:
            run = os.path.join(out, "run")
            r = hil("acquire", "--rig", EXAMPLE_RIG, "--out", run, "--play", EXAMPLE_RUN, "--play-speed", "4", "--play-loop",
                    "--duration", "4")
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            with open(os.path.join(run, "samples.csv")) as f:
                rows = [row for row in csv.DictReader(line for line in f if not line.startswith("#"))]
            t = [float(row["t"]) for row in rows]
            px = [float(row["px"]) for row in rows]
            self.assertGreater(t[-1] - t[0], 3.5)
            starts_over = sum(1 for a, b in zip(px, px[1:]) if a - b > 0.01)
            self.assertEqual(starts_over, 2, (min(px), max(px)))
        finally:
            shutil.rmtree(out)
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--out", os.path.join(out, "x"), "--play-loop")
        self.assertEqual(r.returncode, 2)
        self.assertIn("--play-loop requires --play", r.stderr)

    def test_acquire_check_reads_each_device_once(self):
        import re
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--play", EXAMPLE_RUN, "--check")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        for want in ("serial             FT-FAKE1", "firmware           1.0.42", "counts_per_force   1000\n",
                     "register_map       ur", "server_text        LMB", "joints", "check passed"):
            self.assertIn(want, r.stdout)
        # The pose read over Modbus is the played run's start (pz 0.054 m, moving 4 mm/s), in world.
        m = re.search(r"pose +p \[(\S+), (\S+), (\S+)\] m", r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertAlmostEqual(float(m.group(3)), 0.054, delta=0.003)
        m = re.search(r"wrench +f \[(\S+), (\S+), (\S+)\] N", r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertLess(abs(float(m.group(3))), 5.0)  # no contact yet at the run's start

    def test_acquire_check_scan_finds_a_board_at_the_factory_base_id(self):
        # The example rig with its board at 0x20 (a new board's id): the played fake answers there,
        # and the scan over 0x00-0x7F finds it and nothing else.
        out = tempfile.mkdtemp()
        try:
            with open(EXAMPLE_RIG) as f:
                text = f.read()
            self.assertIn("base_id: 0x00", text)
            rig = os.path.join(out, "rig.yaml")
            with open(rig, "w") as f:
                f.write(text.replace("base_id: 0x00", "base_id: 0x20"))
            r = hil("acquire", "--rig", rig, "--play", EXAMPLE_RUN, "--check", "--scan", "--no-robot")
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            self.assertIn("1 board(s) answered", r.stdout)
            self.assertIn("base id 0x20 (ids 0x200-0x20F)  serial 'FT-FAKE1'", r.stdout)
            self.assertNotIn("set devices.force_plate.base_id", r.stdout)
        finally:
            shutil.rmtree(out)

    def test_acquire_check_names_the_device_that_does_not_answer(self):
        import socket
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()  # nothing listens there now
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--play", EXAMPLE_RUN, "--robot-port", str(port), "--check")
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        robot = r.stdout[r.stdout.index("robot controller"):]
        self.assertIn("FAILED", robot)
        self.assertIn("onnect", robot)  # connect failed: Connection refused
        self.assertIn("serial             FT-FAKE1", r.stdout)  # the plate was still checked
        self.assertIn("check failed", r.stdout)

    def test_acquire_needs_out_unless_check(self):
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--play", EXAMPLE_RUN)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--out", r.stdout + r.stderr)

    def test_acquire_rt_priority(self):
        # Real-time device threads where the process may have them; a clear warning and normal
        # threads where it may not; the acquisition works either way.
        out = tempfile.mkdtemp()
        try:
            env = dict(os.environ)
            env["HIL_DDS_DOMAIN"] = str(160 + os.getpid() % 20)
            r = subprocess.run([HIL, "acquire", "--rig", EXAMPLE_RIG, "--out", os.path.join(out, "run"), "--play", EXAMPLE_RUN,
                                "--duration", "2", "--rt-priority", "10"], capture_output=True, text=True, timeout=120, env=env)
            self.assertEqual(r.returncode, 0, r.stderr)
            for device in ("force_plate", "robot"):
                self.assertRegex(r.stderr, device + r": (device thread at real-time priority 10 \(SCHED_FIFO\)|"
                                 r"real-time priority 10 not permitted \(.+\); the device thread runs at normal priority)")
            self.assertEqual(hil("validate", os.path.join(out, "run")).returncode, 0)
        finally:
            shutil.rmtree(out)
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--out", os.path.join(out, "x"), "--play", EXAMPLE_RUN, "--rt-priority", "100")
        self.assertEqual(r.returncode, 2)
        self.assertIn("--rt-priority", r.stderr)

    def test_acquire_refuses_to_overwrite_a_run(self):
        r = hil("acquire", "--rig", EXAMPLE_RIG, "--out", EXAMPLE_RUN, "--play", EXAMPLE_RUN)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("refusing to overwrite", r.stderr)

    def acquire_then_signal(self, sig):
        import signal, time
        out = tempfile.mkdtemp()
        run = os.path.join(out, "run")
        env = dict(os.environ)
        env["HIL_DDS_DOMAIN"] = str(120 + os.getpid() % 20)
        p = subprocess.Popen([HIL, "acquire", "--rig", EXAMPLE_RIG, "--out", run, "--play", EXAMPLE_RUN, "--duration", "60"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        # From when the devices have started (run.yaml names them), not from the process's start:
        # a slow start (a sanitizer build, a busy machine) must not eat the time being tested.
        yaml_path, deadline = os.path.join(run, "run.yaml"), time.monotonic() + 60 * TIME_SCALE
        while time.monotonic() < deadline and p.poll() is None:
            if os.path.exists(yaml_path) and 'serial: "FT-FAKE1"' in open(yaml_path).read():
                break
            time.sleep(0.05)
        time.sleep(3.0)
        p.send_signal(sig)
        stdout, stderr = p.communicate(timeout=30)
        return out, run, p.returncode, stdout, stderr

    def test_acquire_ctrl_c_closes_cleanly(self):
        import signal
        out, run, rc, stdout, stderr = self.acquire_then_signal(signal.SIGINT)
        try:
            self.assertEqual(rc, 0, stderr)
            r = hil("validate", run)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(run, "run.yaml")) as f:
                text = f.read()
            self.assertIn("Samples:", text)  # the closing summary
            # What the devices said about themselves (docs/hardware.md), under their sources.
            self.assertIn('serial: "FT-FAKE1"', text)
            self.assertIn('firmware: "1.0.42"', text)
            self.assertIn('register_map: "ur"', text)
        finally:
            shutil.rmtree(out)

    def test_acquire_kill_9_leaves_a_readable_run(self):
        import signal
        out, run, rc, stdout, stderr = self.acquire_then_signal(signal.SIGKILL)
        try:
            self.assertEqual(rc, -9)
            r = hil("validate", run)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(run, "run.yaml")) as f:
                self.assertIn('serial: "FT-FAKE1"', f.read())  # written as soon as the devices started
            m = __import__("re").search(r"samples: (\d+), duration ([0-9.]+) s", r.stdout)
            self.assertIsNotNone(m, r.stdout)
            # 3 s after the devices started, flushed every second: at least ~1 s of 50 Hz samples are there.
            self.assertGreaterEqual(int(m.group(1)), 50)
        finally:
            shutil.rmtree(out)

    def test_contact_worker_estimates_online(self):
        env = dict(os.environ)
        env["HIL_DDS_DOMAIN"] = str(230 + os.getpid() % 3)
        with open(os.path.join(EXAMPLE_RUN, "samples.csv")) as f:
            rows = sum(1 for _ in f) - 1
        worker = subprocess.Popen([HIL, "contact", "worker", "--rig", os.path.join(EXAMPLE_RUN, "rig.yaml"),
                                   "--count", str(rows), "--duration", "60"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        r = subprocess.run([HIL, "replay", EXAMPLE_RUN, "--speed", "0", "--wait-subscribers", "1"],
                           capture_output=True, text=True, timeout=120, env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        out, err = worker.communicate(timeout=90)
        self.assertEqual(worker.returncode, 0, err)
        m = __import__("re").search(r"(\d+) samples, running global K = ([0-9.e+]+) .* mu = ([0-9.]+)", out)
        self.assertIsNotNone(m, out)
        self.assertEqual(int(m.group(1)), rows)
        self.assertAlmostEqual(float(m.group(2)) / 1.8e5, 1.0, delta=0.05)
        self.assertAlmostEqual(float(m.group(3)), 0.2, delta=0.03)

    def test_echo_with_nothing_before_its_timeout_fails(self):
        # Nobody publishes contact estimates on this private domain: a script must see that.
        r = hil("echo", "contact_estimate", "--timeout", "1", "--dds-domain", "187")
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("0 messages", r.stderr)

    def test_every_subcommand_lists_and_takes_the_global_options(self):
        for cmd in (["echo"], ["diagnose"], ["stiffness", "worker"], ["replay"], ["rig", "run"]):
            r = hil(*cmd, "--help")
            self.assertEqual(r.returncode, 0, cmd)
            for opt in ("--dds-domain", "--log-level", "--dds-profile"):
                self.assertIn(opt, r.stdout, cmd)
        # After the subcommand as before it, and checked the same way.
        r = hil("echo", "pose_wrench", "--dds-domain", "999", "--timeout", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--dds-domain", r.stderr)

    def test_echo_unknown_topic(self):
        r = hil("echo", "nonsense", "--timeout", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("unknown topic 'nonsense'", r.stderr)

    def test_simulate_refuses_an_unknown_effect(self):
        r = hil("contact", "simulate", "--rig", EXAMPLE_RIG, "--trajectory",
                os.path.join(SRC, "examples", "trajectories", "press_slide.csv"), "--out",
                os.path.join(tempfile.mkdtemp(), "run"), "--inject", "sensor_bias,magnetism")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("magnetism", r.stderr.splitlines()[0])


class BadInput(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.run = os.path.join(self.dir, "run")
        shutil.copytree(EXAMPLE_RUN, self.run)
        with open(os.path.join(self.run, "samples.csv")) as f:
            self.lines = f.read().splitlines()

    def tearDown(self):
        shutil.rmtree(self.dir)

    def write_samples(self, lines, end="\n"):
        with open(os.path.join(self.run, "samples.csv"), "w") as f:
            f.write("\n".join(lines) + end)

    def cell(self, line_no, col, value):
        lines = list(self.lines)
        cells = lines[line_no - 1].split(",")
        cells[self.lines[0].split(",").index(col)] = value
        lines[line_no - 1] = ",".join(cells)
        return lines

    def expect_error(self, *needles):
        r = hil("validate", self.run)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)  # bad input
        self.assertNotIn("Segmentation", r.stderr)
        for n in needles:
            self.assertIn(n, r.stderr)
        return r

    def test_missing_column(self):
        lines = [",".join(c for c in l.split(",")[:-1]) for l in self.lines]
        self.write_samples(lines)
        self.expect_error("samples.csv:1", "'mz'", "missing")

    def test_misspelt_column(self):
        lines = list(self.lines)
        lines[0] = lines[0].replace(",fy,", ",fY,")
        self.write_samples(lines)
        self.expect_error("samples.csv:1", "'fy'", "'fY': misspelt?")

    def test_non_numeric(self):
        self.write_samples(self.cell(10, "fz", "12,5".replace(",", ";")))
        self.expect_error("samples.csv:10:", "'fz'", "expected a number")

    def test_nan(self):
        self.write_samples(self.cell(7, "px", "NaN"))
        self.expect_error("samples.csv:7:", "'px'", "finite")

    def test_non_unit_quaternion(self):
        self.write_samples(self.cell(5, "qw", "0.5"))
        self.expect_error("samples.csv:5:", "not a unit quaternion")

    def test_time_backwards(self):
        self.write_samples(self.cell(20, "t", "0.1"))
        self.expect_error("samples.csv:20", "'t'", "backwards")

    def test_duplicated_timestamp(self):
        t_prev = self.lines[18].split(",")[0]
        self.write_samples(self.cell(20, "t", t_prev))
        self.expect_error("samples.csv:20", "duplicated timestamp")

    def test_truncated_last_line(self):
        lines = list(self.lines)
        lines[-1] = lines[-1][: len(lines[-1]) // 2].rsplit(",", 1)[0]
        self.write_samples(lines, end="")
        self.expect_error("samples.csv:%d" % len(lines), "truncated last line")

    def test_empty_file(self):
        self.write_samples([], end="")
        self.expect_error("samples.csv", "empty file")

    def rig_error(self, old, new, *needles):
        with open(os.path.join(self.run, "rig.yaml")) as f:
            text = f.read()
        self.assertIn(old, text)
        with open(os.path.join(self.run, "rig.yaml"), "w") as f:
            f.write(text.replace(old, new, 1))
        return self.expect_error("rig.yaml:", *needles)

    def test_unknown_rig_field(self):
        self.rig_error("stiffness_n_per_m:", "stifness_n_per_m:", "stifness_n_per_m", "unknown field", "did you mean")

    def test_missing_rig_field(self):
        self.rig_error("  - name: cube\n    frame: object1\n", "  - name: cube\n", "objects[0].frame", "required field is missing")

    def test_degenerate_polyhedron(self):
        top = "[-0.015, -0.015, 0.03], [0.015, -0.015, 0.03], [0.015, 0.015, 0.03], [-0.015, 0.015, 0.03]]"
        self.rig_error(top, top.replace("0.03]", "0.0]"), "vertices_m", "coplanar")

    def test_missing_run_yaml(self):
        os.remove(os.path.join(self.run, "run.yaml"))
        self.expect_error("run.yaml", "missing")


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"] + sys.argv[3:])
