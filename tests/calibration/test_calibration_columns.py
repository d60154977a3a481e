#!/usr/bin/env python3
"""`hil calibrate` on calibration runs written by the independent serial truth (serial_truth_run:
KDL and the equations, no hil code): the flag column reaches flag_offsets, the base inclinometer's
tilt columns reach measured_tilt (without them the base's springs are base_compliance), a clean robot with both columns is `none`, and bad bending links
or tilt columns fail by name. Seeds are fixed development seeds, not the blind suite's."""
import json
import os
import subprocess
import sys
import tempfile
import shutil
import unittest

HIL, GENERATE, SRC = sys.argv[1], sys.argv[2], sys.argv[3]
RIG = os.path.join(SRC, "examples", "robots", "ur10_rig.yaml")


def run(*args, timeout=300):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=timeout)


class CalibrationColumns(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def generate(self, effect, seed):
        out = os.path.join(self.dir, f"{effect}_{seed}.csv")
        r = run(GENERATE, out, effect, str(seed))
        self.assertEqual(r.returncode, 0, r.stderr)
        return out

    def calibrate(self, path, *extra):
        r = run(HIL, "calibrate", path, "--rig", RIG, *extra, "--json", "-")
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout), r.stderr

    def test_flagged_offsets_are_named_from_the_flag_column(self):
        d, text = self.calibrate(self.generate("flag_offsets", 5101))
        self.assertEqual(d["flags"], ["elbow_flipped"])
        self.assertEqual(d["tilts"], ["tilt_base_link_rx", "tilt_base_link_ry"])
        self.assertEqual(d["cause"], "flag_offsets", d["verdict"])
        self.assertTrue(d["noise"]["after_cause"]["within"], d["verdict"])
        names = [p["name"] for p in d["cause_fit"]["parameters"]]
        self.assertIn("offset elbow_joint when elbow_flipped", names)
        self.assertIn("links that may bend (link_bending)", text)

    def test_a_measured_base_tilt_is_applied_not_fitted(self):
        d, _ = self.calibrate(self.generate("base_springs", 5102))
        self.assertEqual(d["cause"], "measured_tilt", d["verdict"])
        self.assertIsNone(d["second_cause"], d["verdict"])
        self.assertTrue(d["noise"]["after_cause"]["within"], d["verdict"])
        # Nothing is fitted for it: the cause's parameters are the stations' and the tool point's.
        self.assertEqual({p["part"] for p in d["cause_fit"]["parameters"]}, {"station", "tool"})

    def test_a_base_on_springs_without_its_inclinometer_is_its_compliance(self):
        # The base_springs run with the tilt columns dropped: the tilt is fitted from the points.
        with_tilts = self.generate("base_springs", 5104)
        d, _ = self.calibrate(with_tilts)
        self.assertTrue(any("base_compliance: the run measures the base's tilt" in s for s in d["skipped"]), d["skipped"])
        without = os.path.join(self.dir, "base_springs_no_tilts.csv")
        with open(with_tilts) as src, open(without, "w") as dst:
            for line in src:
                dst.write(line if line.startswith("#") else ",".join(line.rstrip("\n").split(",")[:-2]) + "\n")
        d, _ = self.calibrate(without)
        self.assertEqual(d["tilts"], [])
        self.assertEqual(d["cause"], "base_compliance", d["verdict"])
        self.assertIsNone(d["second_cause"], d["verdict"])
        self.assertTrue(d["noise"]["after_cause"]["within"], d["verdict"])
        fitted = {p["name"]: p for p in d["cause_fit"]["parameters"] if p["part"] == "base_compliance"}
        self.assertEqual(set(fitted), {"compliance base_link rx", "compliance base_link ry"})
        for p in fitted.values():
            self.assertEqual(p["unit"], "rad/(N·m)")
            self.assertGreater(p["value"], 0.0)  # a spring, k in [2e5, 6e5] N·m/rad: 1.7-5 µrad/(N·m)
            self.assertLess(abs(p["value"] - 3e-6), 3e-6)

    def test_a_clean_robot_with_both_columns_is_none(self):
        d, _ = self.calibrate(self.generate("clean", 5103), "--bending-links", "upper_arm_link,forearm_link")
        self.assertEqual(d["kind"], "none", d["verdict"])
        self.assertIsNone(d["cause"])

    def test_named_bending_links_are_the_ones_compared(self):
        # The stated noise is given, so a run within it stops before the comparison's extras: use
        # the flagged run, which is not within it, and name the links.
        d, _ = self.calibrate(self.generate("flag_offsets", 5101), "--bending-links", "upper_arm_link,forearm_link")
        self.assertTrue(set(d["bending_links"]) <= {"upper_arm_link", "forearm_link"}, d["bending_links"])
        self.assertEqual(len(d["bending_links"]) + len(d["bending_dropped"]), 2)

    def test_bad_bending_links_and_tilt_columns_fail_by_name(self):
        path = self.generate("clean", 5103)
        r = run(HIL, "calibrate", path, "--rig", RIG, "--bending-links", "forearm_lnk")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("bending link 'forearm_lnk' is not a link of the robot's chain", r.stderr)
        r = run(HIL, "calibrate", path, "--rig", RIG, "--orientation")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("the run has no measured orientations", r.stderr)
        r = run(HIL, "calibrate", path, "--rig", RIG, "--bending-links", "base_link")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("is the chain's base", r.stderr)
        bad = os.path.join(self.dir, "bad_tilt.csv")
        with open(path) as f, open(bad, "w") as g:
            g.write(f.read().replace("tilt_base_link_rx", "tilt_base_lnk_rx"))
        r = run(HIL, "calibrate", bad, "--rig", RIG)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("tilt of link 'base_lnk'", r.stderr)
        self.assertIn("bad_tilt.csv", r.stderr)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
