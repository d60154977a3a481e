#!/usr/bin/env python3
"""Runs the real `hil import` on the shipped synthetic example and on the TIAGo data in ../shared:
exit status, summary, the written run, and bad input reported with file, line and field."""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
EX = os.path.join(SRC, "examples", "import")
TIAGO = os.path.join(SRC, "..", "shared", "data", "tiago-suspension", "tiago_xyz_vicon_1640.csv")


def hil(*args):
    return subprocess.run([HIL, *args], capture_output=True, text=True, timeout=120)


class Import(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.out = os.path.join(self.dir, "run")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def test_help(self):
        r = hil("import", "--help")
        self.assertEqual(r.returncode, 0)
        for opt in ("DATA", "--config", "--out", "--rig-name"):
            self.assertIn(opt, r.stdout)

    def test_synthetic_example(self):
        r = hil("import", os.path.join(EX, "synthetic_markers.csv"), "--config", os.path.join(EX, "synthetic.yaml"),
                "--out", self.out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("rows: 101 read, 99 written", r.stdout)
        self.assertIn("dropped 1: duplicated timestamp (first on line 54)", r.stdout)
        self.assertIn("dropped 1: body 'probe' (the ee): 2 of 4 markers seen (first on line 88)", r.stdout)
        self.assertRegex(r.stdout, r"body probe \(ee\): 4 markers, 99 rows fitted \(5 with markers missing\)")
        with open(os.path.join(self.out, "samples.csv")) as f:
            header = f.readline().strip().split(",")
        self.assertEqual(header[:20], "t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,mx,my,mz".split(","))
        self.assertEqual(header[20:], ["probe_fit_rms_m", "probe_markers_seen", "trigger"])
        with open(os.path.join(self.out, "run.yaml")) as f:
            run_yaml = f.read()
        self.assertIn("kind: import", run_yaml)
        self.assertIn("start_time: 2026-11-21T10:00:00.000000Z", run_yaml)
        self.assertIn("rig: synthetic_probe", run_yaml)
        if "validate" in hil("--help").stdout:
            v = hil("validate", self.out)
            self.assertEqual(v.returncode, 0, v.stderr)

    def test_existing_output_and_rig_name(self):
        args = ["import", os.path.join(EX, "synthetic_markers.csv"), "--config", os.path.join(EX, "synthetic.yaml"),
                "--out", self.out]
        self.assertEqual(hil(*args).returncode, 0)
        r = hil(*args)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--force", r.stderr)
        r = hil(*args, "--force", "--rig-name", "bench_7")
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(self.out, "run.yaml")) as f:
            self.assertIn("rig: bench_7", f.read())

    def test_bad_config_and_data(self):
        with open(os.path.join(EX, "synthetic.yaml")) as f:
            cfg = f.read()
        bad_cfg = os.path.join(self.dir, "bad.yaml")
        with open(bad_cfg, "w") as f:
            f.write(cfg.replace("  unit: ms", "  units: ms"))
        r = hil("import", os.path.join(EX, "synthetic_markers.csv"), "--config", bad_cfg, "--out", self.out)
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r"bad\.yaml:\d+:\d+: field 'time\.units': unknown field \(did you mean 'unit'\?\)")
        with open(os.path.join(EX, "synthetic_markers.csv")) as f:
            lines = f.read().splitlines()
        lines[10] = lines[10].replace(",", ",x", 1)
        bad_data = os.path.join(self.dir, "bad.csv")
        with open(bad_data, "w") as f:
            f.write("\n".join(lines) + "\n")
        r = hil("import", bad_data, "--config", os.path.join(EX, "synthetic.yaml"), "--out", self.out)
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r"bad\.csv:11:2: field 'p1_x': expected a number, found 'x")
        self.assertFalse(os.path.exists(os.path.join(self.out, "run.yaml")))

    @unittest.skipUnless(os.path.exists(TIAGO), "shared TIAGo data not present")
    def test_tiago(self):
        r = hil("import", TIAGO, "--config", os.path.join(EX, "tiago_suspension.yaml"), "--out", self.out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("rows: 5547 read, 5547 written", r.stdout)
        self.assertRegex(r.stdout, r"duration 56\.022 s")
        self.assertRegex(r.stdout, r"body base \(ee\): 3 markers, 5547 rows fitted")
        m = re.search(r"fz (-?[\d.]+)\.\.(-?[\d.]+) N", r.stdout)
        self.assertTrue(m, r.stdout)
        self.assertGreater(float(m.group(1)), -840)
        self.assertLess(float(m.group(2)), -620)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]])
