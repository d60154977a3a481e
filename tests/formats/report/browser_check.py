#!/usr/bin/env python3
"""Each kind of hil report, made by the real `hil` from the shipped examples, opened in Debian's
headless Chromium (browser/check_report.mjs): contact identification (the ACU experiment), the diagnosis of a contact
run (with its hidden truth), of a clean one, of a deflection run (TIAGo, when ../shared is beside the
checkout), of a run diagnosed in time windows (its timeline of verdicts) and of a calibration run
(the KR-270-like stiffness table). Each must show its verdict on the first
screen, overflow nowhere, draw every figure, keep every link, log no error and print to PDF; a
screenshot per kind is kept in SHOTS. A deliberately broken page must fail the same check, with
each of its faults named (the check can fail).

usage: browser_check.py HIL SRC NODE CHECKER CHROMIUM SHOTS"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HIL, SRC, NODE, CHECKER, CHROMIUM, SHOTS = sys.argv[1:7]
TIAGO = os.path.join(SRC, "..", "shared", "data", "tiago-suspension", "tiago_xyz_vicon_1640.csv")


# Sanitizer builds run slower (docs/sanitizers.md): their test presets set this factor.
TIME_SCALE = float(os.environ.get("HIL_TEST_TIME_SCALE", "1"))


def run(*args, timeout=600):
    r = subprocess.run(list(args), capture_output=True, text=True, timeout=timeout * TIME_SCALE)
    return r


class Reports(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir)

    def hil(self, *args):
        r = run(HIL, *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        return r

    def check(self, kind, report, min_figures, *expect):
        r = run(NODE, CHECKER, CHROMIUM, SHOTS, kind, os.path.join(report, "index.html"), str(min_figures), *expect)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertTrue(os.path.getsize(os.path.join(SHOTS, kind + ".png")) > 10000)
        return r

    def simulated(self, name, *inject):
        out = os.path.join(self.dir, name)
        args = ["contact", "simulate", "--rig", os.path.join(SRC, "examples", "rigs", "press_bench.yaml"), "--trajectory",
                os.path.join(SRC, "examples", "trajectories", "press_slide.csv"), "--out", out, "--force-resolution", "0.1",
                "--force-noise", "0.1", "--moment-resolution", "0.005", "--moment-noise", "0.005", "--seed", "11"]
        if inject:
            args += ["--inject", ",".join(inject), "--effect-seed", "12", "--truth-out", out + ".truth.json"]
        self.hil(*args)
        return out

    def test_contact_identification(self):
        # The ACU experiment (hil demo's): nine geometric uncertainties, so the observability
        # tables are as wide as a lab's scene makes them.
        run_dir = os.path.join(self.dir, "ident")
        self.hil("contact", "simulate", "--rig", os.path.join(SRC, "examples", "acu", "acu.yaml"), "--trajectory",
                 os.path.join(SRC, "examples", "acu", "traj_2a.csv"), "--decimate", "20", "--out", run_dir, "--force-resolution", "1.5",
                 "--force-noise", "0.3", "--moment-resolution", "0.05", "--moment-noise", "0.02", "--seed", "17")
        rep = os.path.join(self.dir, "ident-report")
        self.hil("contact", "identify", run_dir, "--geometric", "--report", rep)
        self.check("contact-identification", rep, 10, "K = ", "force error", "Parameters", "fig:Identified parameters",
                   "fig:L-curve", "The summary as `hil contact identify` prints it")

    def test_diagnosis_of_a_contact_run(self):
        run_dir = self.simulated("bias", "sensor_bias")
        rep = os.path.join(self.dir, "bias-report")
        self.hil("diagnose", run_dir, "--report", rep, "--truth", run_dir + ".truth.json", "--quiet")
        self.check("diagnosis-contact", rep, 10, "Named cause: sensor_bias", "held-out error", "gain", "stability", "Next:",
                   "truth", "fig:Held-out error of each candidate", "fig:Parameters: value and 95 % interval",
                   "fig:Residual of", "fig:Autocorrelation", "1 contact, sliding")

    def test_diagnosis_of_a_clean_contact_run(self):
        run_dir = self.simulated("clean")
        rep = os.path.join(self.dir, "clean-report")
        self.hil("diagnose", run_dir, "--report", rep, "--quiet")
        self.check("diagnosis-none", rep, 8, "No cause", "Next: nothing to change")

    @unittest.skipUnless(os.path.exists(TIAGO), "../shared/data/tiago-suspension is not beside this checkout")
    def test_diagnosis_of_a_deflection_run(self):
        run_dir = os.path.join(self.dir, "tiago")
        self.hil("import", TIAGO, "--config", os.path.join(SRC, "examples", "import", "tiago_suspension.yaml"), "--out", run_dir)
        rep = os.path.join(self.dir, "tiago-report")
        # Under ASan + UBSan (HIL_SANITIZE) 2 grid offsets keep it within its time; the page is the same kind.
        offsets = "2" if os.environ.get("HIL_SANITIZE") else "4"
        self.hil("diagnose", run_dir, "--rig", os.path.join(SRC, "examples", "import", "tiago_suspension_rig.yaml"), "--report", rep,
                 "--cv-offsets", offsets, "--quiet")
        self.check("diagnosis-deflection", rep, 10, "Named cause:", "offsets of the CV grid", "deflection model",
                   "Located events", "fig:Autocorrelation")

    def test_windowed_diagnosis(self):
        sys.path.insert(0, os.path.join(SRC, "tests", "diagnosis"))
        import step_bias_run
        run_dir = os.path.join(self.dir, "step")
        step_bias_run.make(HIL, SRC, run_dir, seed=53, offset_n=4.0, t_step_s=13.0)
        rep = os.path.join(self.dir, "step-report")
        self.hil("diagnose", run_dir, "--window", "6.5", "--report", rep, "--quiet")
        self.check("diagnosis-windows", rep, 10, "Over time (4 windows)", "over time", "sensor_bias from 13.0 s",
                   "fig:Verdict per window", "fig:Held-out error per window")

    def test_diagnosis_of_a_calibration_run(self):
        rep = os.path.join(self.dir, "stiffness-report")
        self.hil("diagnose", os.path.join(SRC, "examples", "stiffness", "table.csv"), "--rig",
                 os.path.join(SRC, "examples", "stiffness", "kr270_like.yaml"), "--report", rep, "--quiet")
        self.check("diagnosis-calibration", rep, 10, "Named cause: link_compliance", "Residual vectors per configuration",
                   "fig:Translation residual per configuration", "fig:Translation residual vectors, x-y plane",
                   "largest nominal residual")

    def test_a_broken_page_fails_with_each_fault_named(self):
        bad = os.path.join(self.dir, "bad")
        os.makedirs(bad)
        with open(os.path.join(bad, "index.html"), "w") as f:
            f.write("<!DOCTYPE html><html><head><meta charset='utf-8'><title>bad</title></head><body>"
                    "<div style='height:1200px'></div><section id='verdict'><p class='headline'>too low</p></section>"
                    "<a href='#nowhere'>a dangling link</a><a href='https://example.com/x'>away</a>"
                    "<pre style='width:2000px'>a line wider than any window</pre>"
                    "<figure class='fig' id='fig-1'></figure>"
                    "<script>console.error('boom')</script></body></html>")
        r = run(NODE, CHECKER, CHROMIUM, os.path.join(self.dir, "bad-shots"), "broken", os.path.join(bad, "index.html"), "2",
                "a text the page lacks")
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        for fault in ("not on the first screen", "the page is", "broken link: #nowhere", "broken link: https://example.com/x",
                      "figure fig-1 has no SVG", "1 figures, expected at least 2", "console error: boom",
                      'missing text: "a text the page lacks"'):
            self.assertIn(fault, r.stderr)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
