#!/usr/bin/env python3
"""A URDF robot through the commands: the KR-270-like robot's rig with its robot from a URDF
(examples/stiffness/kr270_like_urdf.yaml) validates, simulates, identifies and diagnoses exactly as
the rig with the same robot as a DH table; a rig whose URDF is missing or wrong fails by name."""
import json
import os
import subprocess
import sys
import tempfile
import shutil
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
EX = os.path.join(SRC, "examples", "stiffness")
DH_RIG = os.path.join(EX, "kr270_like.yaml")
URDF_RIG = os.path.join(EX, "kr270_like_urdf.yaml")
TABLE = os.path.join(EX, "table.csv")
UR10_DATA = os.path.join(SRC, "..", "shared", "data", "ur10-calibration", "calibration.csv")
UR10_RIG = os.path.join(SRC, "examples", "robots", "ur10_rig.yaml")
UR10_MAP = os.path.join(SRC, "examples", "import", "ur10_calibration.yaml")


def hil(*args, timeout=300):
    return subprocess.run([HIL, *args], capture_output=True, text=True, timeout=timeout)


class UrdfRobot(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def import_ur10(self):
        """The real UR10 postures as a calibration run (skips when ../shared is not beside the clone)."""
        if not os.path.exists(UR10_DATA):
            self.skipTest("the shared UR10 data is not beside the clone")
        out = os.path.join(self.dir, "ur10.csv")
        r = hil("import", UR10_DATA, "--config", UR10_MAP, "--rig", UR10_RIG, "--out", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        return out, r

    def json_of(self, *args):
        r = hil(*args, "--json", "-")
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def test_validate_names_the_urdf_chain(self):
        d = self.json_of("validate", URDF_RIG)
        self.assertEqual(d["kind"], "rig")
        robot = d["summary"]["robot"]
        self.assertEqual(robot["convention"], "urdf")
        self.assertEqual(robot["joints"], 6)
        self.assertEqual((robot["base_link"], robot["tip_link"]), ("base_link", "tool0"))
        r = hil("validate", URDF_RIG)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("URDF base_link -> tool0", r.stdout + r.stderr)

    def test_simulate_and_identify_agree_with_the_dh_rig(self):
        truth = os.path.join(EX, "truth.json")
        tables = {}
        for name, rig in (("dh", DH_RIG), ("urdf", URDF_RIG)):
            out = os.path.join(self.dir, name + ".csv")
            r = hil("stiffness", "simulate", "--rig", rig, "--truth", truth, "--seed", "11", "--configs", "40", "--out", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out) as f:
                tables[name] = [line for line in f if not line.startswith("#")]
        self.assertEqual(len(tables["dh"]), 41)
        # Same robot, same seed: the same table, number for number, up to the last digits of the
        # floating-point sums (the two forms multiply the transforms in different orders).
        for a, b in zip(tables["dh"][1:], tables["urdf"][1:]):
            for x, y in zip(a.split(","), b.split(",")):
                self.assertAlmostEqual(float(x), float(y), delta=1e-9 * max(1.0, abs(float(x))))
        ident = {name: self.json_of("stiffness", "identify", TABLE, "--rig", rig, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5")
                 for name, rig in (("dh", DH_RIG), ("urdf", URDF_RIG))}
        self.assertEqual(ident["urdf"]["robot"]["convention"], "urdf")
        self.assertEqual(ident["dh"]["rank"], ident["urdf"]["rank"])
        pa = {p["name"]: p["value"] for p in ident["dh"]["parameters"]}
        pb = {p["name"]: p["value"] for p in ident["urdf"]["parameters"]}
        self.assertEqual(pa.keys(), pb.keys())
        for k in pa:
            self.assertAlmostEqual(pa[k], pb[k], delta=1e-6 * abs(pa[k]), msg=k)
        # The identified model keeps its URDF robot: predict reads it back.
        model = os.path.join(self.dir, "model.json")
        with open(model, "w") as f:
            json.dump(ident["urdf"], f)
        r = hil("stiffness", "predict", model, "--data", os.path.join(EX, "configs.csv"), "--out", "-")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertGreater(len(r.stdout.splitlines()), 2)

    def test_diagnosis_names_the_same_cause(self):
        d = {name: self.json_of("diagnose", TABLE, "--rig", rig, "--quiet") for name, rig in (("dh", DH_RIG), ("urdf", URDF_RIG))}
        self.assertEqual(d["urdf"]["mode"], "stiffness")
        self.assertEqual(d["urdf"]["cause"]["name"], "link_compliance")
        self.assertEqual(d["urdf"]["cause"]["name"], d["dh"]["cause"]["name"])
        self.assertAlmostEqual(d["urdf"]["gain_percent"], d["dh"]["gain_percent"], delta=1e-6)

    def test_bad_urdf_sections_fail_by_name(self):
        rig = os.path.join(self.dir, "rig.yaml")
        with open(rig, "w") as f:
            f.write("format_version: 1\nname: r\nrobot:\n  urdf: %s\n  base_link: base_link\n  tip_link: hand\n"
                    % os.path.join(EX, "kr270_like.urdf"))
        r = hil("validate", rig)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("rig.yaml:4", r.stderr)
        self.assertIn("no link 'hand'", r.stderr)
        self.assertIn("tool0", r.stderr)  # the links it has
        with open(rig, "w") as f:
            f.write("format_version: 1\nname: r\nrobot:\n  urdf: missing.urdf\n  base_link: a\n  tip_link: b\n")
        r = hil("stiffness", "identify", TABLE, "--rig", rig)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn(os.path.join(self.dir, "missing.urdf"), r.stderr)
        self.assertIn("cannot open", r.stderr)


    def test_a_mimic_joint_is_simulated_and_identified_as_a_physical_joint(self):
        # The palletizer's wrist pitch follows its elbow (multiplier -1): planned postures obey the
        # coupling, and the passive joint's own spring (J4) is identified beside the others.
        rig = os.path.join(SRC, "examples", "robots", "palletizer_mimic.yaml")
        r = hil("validate", rig)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("mimic joint wrist_pitch = -1 × elbow +0", r.stdout)
        truth = os.path.join(self.dir, "truth.json")
        springs = {"J1": 0.5e-6, "J2": 0.8e-6, "J3": 1.2e-6, "J4": 2.0e-6, "J5": 3.0e-6}
        with open(truth, "w") as f:
            json.dump({"format": "hil-stiffness-model", "version": 1, "springs": springs}, f)
        table = os.path.join(self.dir, "table.csv")
        r = hil("stiffness", "simulate", "--rig", rig, "--truth", truth, "--configs", "40", "--moment-nm", "300", "--seed", "5",
                "--out", table)
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = [line.strip().split(",") for line in open(table) if not line.startswith("#")]
        head = rows[0]
        for row in rows[1:]:
            self.assertEqual(float(row[head.index("j4")]), -float(row[head.index("j3")]))
        ident = self.json_of("stiffness", "identify", table, "--rig", rig, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5")
        self.assertEqual(ident["robot"]["joints"][3]["mimic"], {"joint": "elbow", "multiplier": -1.0, "offset": 0.0})
        # Each joint spring is aggregated into the link before it (M3): J4's into L3, about its axis.
        got = {p["name"]: (p["value"], p["std"]) for p in ident["parameters"]}
        self.assertIn("L3.k66", got)
        value, std = got["L3.k66"]
        self.assertLess(abs(value - springs["J4"]), 4 * std)
        # A lab's log has the driven joints only: the import leaves the passive one out, the run's
        # reader derives it, and a derived value beyond the passive joint's limits is refused.
        src, cfg, run = (os.path.join(self.dir, n) for n in ("lab.csv", "map.yaml", "run.csv"))
        with open(src, "w") as f:
            f.write("x;y;z;base_yaw;shoulder;elbow;flange_yaw\n1000;200;1200;10;20;-30;45\n1010;210;1190;11;21;-20;44\n")
        with open(cfg, "w") as f:
            f.write("format_version: 1\nkind: calibration_run\ncsv: {delimiter: ';'}\npoint: {columns: [x, y, z], unit: mm}\n"
                    "joints: {unit: deg}\n")
        r = hil("import", src, "--config", cfg, "--rig", rig, "--out", run)
        self.assertEqual(r.returncode, 0, r.stderr)
        header = [line for line in open(run) if not line.startswith("#")][0].strip().split(",")
        self.assertNotIn("wrist_pitch", header)
        r = hil("validate", run, "--rig", rig)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(src, "w") as f:
            f.write("x;y;z;base_yaw;shoulder;elbow;flange_yaw\n1000;200;1200;10;20;50;45\n")
        r = hil("import", src, "--config", cfg, "--rig", rig, "--out", run + ".2")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("joint 'wrist_pitch' mimics 'elbow'", r.stderr)
        self.assertIn("outside its limits", r.stderr)

    def test_the_real_ur10_table_imports_into_a_calibration_run(self):
        out, r = self.import_ur10()
        rig = UR10_RIG
        self.assertIn("23 postures of robot 'ur10'", r.stdout)
        d = self.json_of("validate", out, "--rig", rig)
        self.assertEqual(d["kind"], "calibration_run")
        s = d["summary"]
        self.assertEqual((s["postures"], s["orientation"], s["stations"]), (23, True, [{"id": "figaroh", "postures": 23}]))
        self.assertEqual(s["joints"][0], "shoulder_pan_joint")
        # The rotation vectors are the roll-pitch-yaw angles of the source, converted (first row:
        # rpy -1.1869 -0.5110 -2.3796, i.e. R = Rz(yaw) Ry(pitch) Rx(roll)), checked here with numpy.
        import numpy as np
        with open(out) as f:
            rows = [line.rstrip("\n").split(",") for line in f if not line.startswith("#")]
        head, first = rows[0], dict(zip(rows[0], rows[1]))
        self.assertEqual(head[:2], ["posture", "station"])
        rv = np.array([float(first[c]) for c in ("rx", "ry", "rz")])
        roll, pitch, yaw = -1.1869330161318221, -0.5109858420062574, -2.3796294050596307

        def rot(axis, a):
            c, s_ = np.cos(a), np.sin(a)
            m = {"x": [[1, 0, 0], [0, c, -s_], [0, s_, c]], "y": [[c, 0, s_], [0, 1, 0], [-s_, 0, c]], "z": [[c, -s_, 0], [s_, c, 0], [0, 0, 1]]}
            return np.array(m[axis])
        R = rot("z", yaw) @ rot("y", pitch) @ rot("x", roll)
        th = np.linalg.norm(rv)
        k = rv / th
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        Rv = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K
        self.assertLess(np.abs(Rv - R).max(), 1e-12)
        self.assertAlmostEqual(float(first["px"]), 0.9088284523365023, delta=1e-15)
        # Once written, not again without --force.
        r = hil("import", UR10_DATA, "--config", UR10_MAP, "--rig", rig, "--out", out)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--force", r.stderr)

    def test_the_real_ur10_calibration_names_what_the_rigid_urdf_misses(self):
        run, _ = self.import_ur10()
        rig = UR10_RIG
        report = os.path.join(self.dir, "report")
        d = self.json_of("calibrate", run, "--rig", rig, "--report", report)
        with open(os.path.join(report, "index.html")) as f:
            html = f.read()
        self.assertIn("What the rigid model misses: geometric", html)
        self.assertIn("What the postures determine", html)
        self.assertIn("offset shoulder_pan_joint", html)
        figures = sorted(os.listdir(os.path.join(report, "figures")))
        self.assertTrue(any("residual-vectors-x-y" in f for f in figures), figures)
        # Per joint: the residual against each joint's value, before and after, one figure each.
        for joint in ("shoulder-pan-joint", "elbow-joint", "wrist-3-joint"):
            csvs = [f for f in figures if f"residual-against-{joint}" in f and f.endswith(".csv")]
            self.assertEqual(len(csvs), 1, figures)
            with open(os.path.join(report, "figures", csvs[0])) as f:
                lines = f.read().strip().splitlines()
            self.assertEqual(len(lines), 1 + 23)  # a header and one row per posture
            self.assertIn("geometric", lines[0])
        self.assertTrue(any("per-posture" in f and f.endswith(".csv") for f in figures), figures)
        # The figures for the nominal URDF with a fitted measurement frame and tool point.
        self.assertAlmostEqual(d["rigid"]["rms_m"] * 1e3, 10.9, delta=0.05)
        self.assertAlmostEqual(d["rigid"]["max_m"] * 1e3, 16.9, delta=0.1)
        determined = {x["model"]: x for x in d["determined"]}
        self.assertEqual(determined["rigid"]["undetermined"], [])
        # A point on the tool cannot tell the first joint's offset from the station's turn about
        # the base's vertical, nor the last joint's from where the point sits on the tool.
        offsets = [t["parameter"] for u in determined["joint_offsets"]["undetermined"] for t in u["terms"]]
        self.assertIn("offset shoulder_pan_joint", offsets)
        self.assertIn("station figaroh rz", offsets)
        self.assertIn("offset wrist_3_joint", offsets)
        # Gravity cannot load the vertical first axis: its compliance is undetermined.
        self.assertIn("compliance shoulder_pan_joint",
                      [t["parameter"] for u in determined["joint_compliance"]["undetermined"] for t in u["terms"]])
        self.assertEqual(d["scheme"], "leave one posture out")
        self.assertEqual(d["cause"], "geometric")
        held = {h["model"]: h for h in d["held_out"]}
        self.assertLess(held["geometric"]["rms_m"], 0.5 * held["rigid"]["rms_m"])
        self.assertTrue(all(p["std"] is None for p in d["cause_fit"]["parameters"] if not p["identifiable"]))
        # Bad options are named, with what was expected.
        r = hil("calibrate", run, "--rig", rig, "--tool-point", "0.1,0.2")
        self.assertEqual(r.returncode, 2)
        self.assertIn("expected X,Y,Z in metres, found '0.1,0.2'", r.stderr)
        r = hil("calibrate", run, "--rig", rig, "--candidates", "joint_offsets,bending")
        self.assertEqual(r.returncode, 2)
        self.assertIn("unknown candidate 'bending'", r.stderr)
        r = hil("calibrate", run, "--rig", os.path.join(EX, "kr270_like.yaml"))
        self.assertEqual(r.returncode, 2)  # the run's joints are not that robot's
        self.assertIn("'a1'", r.stderr)

    def test_a_dropped_bending_link_is_not_in_the_named_fit(self):
        # On the real UR10 the forearm's 1/EI fitted to every posture is below zero: the forearm is
        # dropped before the comparison, and the named link_bending's parameters are of the links kept.
        run, _ = self.import_ur10()
        d = self.json_of("calibrate", run, "--rig", UR10_RIG, "--candidates", "link_bending")
        self.assertEqual(d["cause"], "link_bending", d["verdict"])
        self.assertEqual(d["bending_links"], ["shoulder_link", "upper_arm_link"])
        self.assertTrue(any(s.startswith("bending forearm_link dropped") for s in d["bending_dropped"]), d["bending_dropped"])
        bent = [p["name"] for p in d["cause_fit"]["parameters"] if p["part"] == "link_bending"]
        self.assertEqual(bent, ["bending shoulder_link", "bending upper_arm_link"])

    def test_the_real_ur10_orientations_are_fitted_when_asked(self):
        run, _ = self.import_ur10()
        d = self.json_of("calibrate", run, "--rig", UR10_RIG, "--orientation", "--candidates", "joint_offsets,geometric")
        self.assertTrue(d["orientation"])
        self.assertEqual(d["rigid"]["orientations"], 23)
        self.assertEqual(d["cause"], "geometric")
        # The named model explains the orientations too, though only the points decide the verdict.
        self.assertLess(d["cause_fit"]["rms_rad"], 0.8 * d["rigid"]["rms_rad"])
        # The measured frame is a large turn on the tool (the device's frame, not the flange's).
        self.assertGreater(sum(x * x for x in d["rigid"]["tool_rotation_ee_rad"]) ** 0.5, 1.0)
        self.assertFalse(self.json_of("calibrate", run, "--rig", UR10_RIG, "--candidates", "joint_offsets")["orientation"])

    def with_sigma(self, run, sigma_m):
        """The run with a stated noise: a sigma_m column on every posture."""
        out = os.path.join(self.dir, f"sigma_{sigma_m}.csv")
        with open(run) as f, open(out, "w") as g:
            header = True
            for line in f:
                if line.startswith("#") or not line.strip():
                    g.write(line)
                    continue
                g.write(line.rstrip("\n") + (",sigma_m\n" if header else f",{sigma_m}\n"))
                header = False
        return out

    def test_the_stated_noise_decides_none(self):
        run, _ = self.import_ur10()
        d = self.json_of("calibrate", self.with_sigma(run, 0.0005), "--rig", UR10_RIG, "--candidates", "joint_offsets,geometric")
        self.assertEqual(d["kind"], "cause")
        self.assertFalse(d["noise"]["within"])
        self.assertGreater(d["noise"]["rms_over_sigma"], 10)  # 10.9 mm RMS of 3-D distance against 0.5 mm per coordinate
        # The geometric set leaves 2.6 mm RMS: still above a 0.5 mm device, and the verdict says so.
        self.assertFalse(d["noise"]["after_cause"]["within"])
        self.assertIn("something else remains", d["verdict"])
        # A device stated 20 mm per coordinate: the rigid model is within it, nothing is named.
        d = self.json_of("calibrate", self.with_sigma(run, 0.02), "--rig", UR10_RIG, "--candidates", "joint_offsets,geometric")
        self.assertEqual(d["kind"], "none")
        self.assertIsNone(d["cause"])
        self.assertTrue(d["noise"]["within"])
        self.assertIn("within the stated measurement noise", d["verdict"])
        # Without a stated noise the JSON says so.
        d = self.json_of("calibrate", run, "--rig", UR10_RIG, "--candidates", "joint_offsets")
        self.assertIsNone(d["noise"])

    def test_calibration_imports_fail_where_the_problem_is(self):
        rig = UR10_RIG
        src = os.path.join(self.dir, "lab.csv")
        cfg = os.path.join(self.dir, "map.yaml")
        joints = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
        with open(src, "w") as f:
            f.write("x;y;z;" + ";".join(joints) + "\n1000;200;1200;10;-80;90;0;45;0\n1010;;1190;11;-81;89;0;44;0\n")
        with open(cfg, "w") as f:
            f.write("format_version: 1\nkind: calibration_run\ncsv: {delimiter: ';'}\npoint: {columns: [x, y, z], unit: mm}\n"
                    "joints: {unit: deg}\n")
        out = os.path.join(self.dir, "run.csv")
        r = hil("import", src, "--config", cfg, "--rig", rig, "--out", out)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("lab.csv:3:2", r.stderr)  # the empty y cell, where it is in the source
        self.assertFalse(os.path.exists(out))
        with open(src, "w") as f:
            f.write("x;y;z;" + ";".join(joints) + "\n1000;200;1200;10;-80;90;0;45;0\n")
        # Degrees taken as radians: the strict reader refuses the joint value, asking about degrees.
        with open(cfg, "w") as f:
            f.write("format_version: 1\nkind: calibration_run\ncsv: {delimiter: ';'}\npoint: {columns: [x, y, z], unit: mm}\n")
        r = hil("import", src, "--config", cfg, "--rig", rig, "--out", out)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("degrees?", r.stderr)
        with open(cfg, "w") as f:
            f.write("format_version: 1\nkind: calibration_run\ncsv: {delimiter: ';'}\npoint: {columns: [x, y, z]}\n"
                    "joints: {columns: {elbow: q3}}\n")
        r = hil("import", src, "--config", cfg, "--rig", rig, "--out", out)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("no joint 'elbow'", r.stderr)
        r = hil("import", src, "--config", cfg, "--out", out)
        self.assertIn("--rig", r.stderr)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
