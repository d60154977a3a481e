#!/usr/bin/env python3
"""Every JSON hil writes, produced by the real commands on the shipped examples, validated against
its schema in docs/schemas/ (python3-jsonschema); `--json -` gives only JSON on stdout; the report's
figures carry their data as CSV; a stiffness model reader refuses JSON of another kind."""
import csv
import glob
import json
import os
import subprocess
import sys
import tempfile
import shutil
import unittest

import jsonschema

HIL, SRC = sys.argv[1], sys.argv[2]
EX = os.path.join(SRC, "examples")
RUN = os.path.join(EX, "runs", "press_slide")
RIG = os.path.join(EX, "rigs", "press_bench.yaml")
TRAJ = os.path.join(EX, "trajectories", "press_slide.csv")
KR_RIG = os.path.join(EX, "stiffness", "kr270_like.yaml")
TABLE = os.path.join(EX, "stiffness", "table.csv")
KINDS = ("validation", "diagnosis", "contact_identification", "stiffness_model", "hidden_effects", "point_calibration")


def hil(*args, timeout=300):
    return subprocess.run([HIL, *args], capture_output=True, text=True, timeout=timeout)


def schema(kind):
    with open(os.path.join(SRC, "docs", "schemas", "hil.%s.schema.json" % kind)) as f:
        return json.load(f)


class JsonOutputs(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.dir)

    def check(self, kind, doc):
        """Valid against the schema of its kind, and tagged with that kind."""
        jsonschema.validate(doc, schema(kind), cls=jsonschema.Draft202012Validator)
        self.assertEqual(doc["format"], "hil." + kind)
        self.assertEqual(doc["format_version"], 1)
        return doc

    def stdout_json(self, r):
        """--json -: the whole of stdout is one JSON document."""
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def test_schemas_are_valid_and_listed(self):
        for kind in KINDS:
            jsonschema.Draft202012Validator.check_schema(schema(kind))
            self.assertEqual(schema(kind)["properties"]["format"]["const"], "hil." + kind)
        found = sorted(os.path.basename(p) for p in glob.glob(os.path.join(SRC, "docs", "schemas", "*.schema.json")))
        self.assertEqual(found, sorted("hil.%s.schema.json" % k for k in KINDS))
        with open(os.path.join(SRC, "docs", "cli.md")) as f:
            doc = f.read()
        for kind in KINDS:
            self.assertIn("hil.%s.schema.json" % kind, doc)

    def test_validation(self):
        # Each kind of input; a bare --json is stdout too.
        d = self.check("validation", self.stdout_json(hil("validate", RUN, "--json", "-")))
        self.assertTrue(d["ok"])
        self.assertEqual(d["kind"], "run")
        self.assertEqual(d["summary"]["samples"]["count"], 325)
        self.assertAlmostEqual(d["summary"]["samples"]["rate_hz"], 50.0, places=2)
        self.assertEqual(d["summary"]["rig"]["polyhedra"], 2)
        d = self.check("validation", self.stdout_json(hil("validate", RIG, "--json")))
        self.assertEqual((d["kind"], d["summary"]["robot"]["joints"]), ("rig", 6))
        d = self.check("validation", self.stdout_json(hil("validate", os.path.join(RUN, "samples.csv"), "--json")))
        self.assertEqual(d["kind"], "samples")
        out = os.path.join(self.dir, "v.json")
        r = hil("validate", os.path.join(RUN, "run.yaml"), "--json", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("OK", r.stdout)  # with a file, the text stays on stdout
        with open(out) as f:
            self.assertEqual(self.check("validation", json.load(f))["kind"], "run_info")
        # An MCAP recording: its channels and counts; cut, refused with what --recover saves.
        mcap = os.path.join(self.dir, "run.mcap")
        self.assertEqual(hil("export", RUN, "--mcap", mcap, "--compression", "none").returncode, 0)
        d = self.check("validation", self.stdout_json(hil("validate", mcap, "--json", "-")))
        self.assertEqual((d["kind"], d["summary"]["profile"]), ("mcap", "ros2"))
        counts = {c["topic"]: c["messages"] for c in d["summary"]["channels"]}
        self.assertEqual((counts["/hil/pose_wrench"], counts["/tf"], counts["/tf_static"]), (325, 325, 1))
        self.assertEqual(d["summary"]["messages"], sum(counts.values()))
        self.assertAlmostEqual(d["summary"]["duration_s"], 6.48, places=6)
        with open(mcap, "rb") as f:
            data = f.read()
        cut = os.path.join(self.dir, "cut.mcap")
        with open(cut, "wb") as f:
            f.write(data[: len(data) * 2 // 3])
        r = hil("validate", cut, "--json", "-")
        self.assertEqual(r.returncode, 2, r.stderr)
        d = self.check("validation", json.loads(r.stdout))
        self.assertEqual((d["ok"], d["kind"]), (False, "mcap"))
        self.assertRegex(d["errors"][0]["message"], r"hil export --recover .*cut\.mcap --mcap OUT saves \d+ messages in \d+ chunks")

    def test_validation_failure_still_writes_the_json(self):
        run = os.path.join(self.dir, "run")
        shutil.copytree(RUN, run)
        with open(os.path.join(run, "samples.csv")) as f:
            lines = f.read().splitlines()
        head = lines[0].split(",")
        cells = lines[9].split(",")
        cells[head.index("fz")] = "x"
        lines[9] = ",".join(cells)
        with open(os.path.join(run, "samples.csv"), "w") as f:
            f.write("\n".join(lines) + "\n")
        r = hil("validate", run, "--json", "-")
        self.assertEqual(r.returncode, 2, r.stderr)
        d = self.check("validation", json.loads(r.stdout))
        self.assertFalse(d["ok"])
        self.assertIsNone(d["summary"])
        e = d["errors"][0]
        self.assertTrue(e["file"].endswith("samples.csv"), e)
        self.assertEqual((e["line"], e["field"]), (10, "fz"))
        self.assertIn("expected a number", e["message"])
        self.assertIn("samples.csv:10:", r.stderr)  # and the usual line on stderr
        # A path that does not exist: kind unknown, still exit 2.
        r = hil("validate", os.path.join(self.dir, "nothing"), "--json", "-")
        self.assertEqual(r.returncode, 2, r.stderr)
        d = self.check("validation", json.loads(r.stdout))
        self.assertEqual((d["ok"], d["kind"]), (False, None))
        self.assertIn("no such file", d["errors"][0]["message"])

    def test_diagnosis_and_its_report_data(self):
        rep = os.path.join(self.dir, "report")
        r = hil("diagnose", RUN, "--candidates", "sensor_bias,time_offset", "--folds", "2", "--quiet", "--json", "-",
                "--report", rep)
        d = self.check("diagnosis", self.stdout_json(r))
        self.assertEqual(d["mode"], "contact")
        self.assertEqual({c["name"] for c in d["candidates"]}, {"sensor_bias", "time_offset"})
        self.assertIn("cause:", r.stderr)  # the summary went to stderr
        self.assertIn("report:", r.stderr)
        # Every figure has its data beside it; a component over time (measured and predicted)
        # holds every sample, not the drawing's decimated points.
        svgs = sorted(glob.glob(os.path.join(rep, "figures", "*.svg")))
        self.assertTrue(svgs)
        for svg in svgs:
            self.assertTrue(os.path.exists(svg[:-4] + ".csv"), svg)
        # The figures after the candidates' bars, the parameters' forest and the residual structure:
        # the six components, named by their component.
        series = [s for s in svgs if os.path.basename(s)[3:] in ("fx.svg", "fy.svg", "fz.svg", "mx.svg", "my.svg", "mz.svg")]
        self.assertEqual(len(series), 6, svgs)
        with open(series[0][:-4] + ".csv") as f:
            rows = list(csv.reader(f))
        self.assertEqual(rows[0][0], "t (s)")
        self.assertIn("measured", rows[0][1])
        self.assertEqual(len(rows) - 1, d["samples"])
        self.assertTrue(all(len(row) == len(rows[0]) for row in rows))

    def test_stiffness_table_diagnosis(self):
        r = hil("diagnose", TABLE, "--rig", KR_RIG, "--candidates", "sensor_bias", "--folds", "2", "--quiet", "--json", "-")
        self.assertEqual(self.check("diagnosis", self.stdout_json(r))["mode"], "stiffness")

    def test_point_calibration(self):
        # The real UR10 postures (../shared beside the clone), imported, then calibrated with two
        # quick candidates; and the calibration run's validation summary.
        data = os.path.join(SRC, "..", "shared", "data", "ur10-calibration", "calibration.csv")
        if not os.path.exists(data):
            self.skipTest("the shared UR10 data is not beside the clone")
        rig = os.path.join(EX, "robots", "ur10_rig.yaml")
        run = os.path.join(self.dir, "ur10.csv")
        r = hil("import", data, "--config", os.path.join(EX, "import", "ur10_calibration.yaml"), "--rig", rig, "--out", run)
        self.assertEqual(r.returncode, 0, r.stderr)
        r = hil("validate", run, "--rig", rig, "--json", "-")
        self.assertEqual(self.check("validation", self.stdout_json(r))["kind"], "calibration_run")
        r = hil("calibrate", run, "--rig", rig, "--candidates", "joint_offsets,backlash", "--folds", "4", "--json", "-")
        d = self.check("point_calibration", self.stdout_json(r))
        self.assertEqual(d["scheme"], "4-fold over postures")
        self.assertEqual([h["model"] for h in d["held_out"]][:3], ["rigid", "joint_offsets", "backlash"])
        self.assertIn("what the postures determine", r.stderr)

    def test_contact_identification(self):
        rep = os.path.join(self.dir, "report")
        r = hil("contact", "identify", RUN, "--json", "-", "--report", rep)
        d = self.check("contact_identification", self.stdout_json(r))
        self.assertGreater(d["K"], 0)
        self.assertEqual(d["samples"], 325)
        self.assertIn("report:", r.stderr)
        # Series on different x (instantaneous estimates, a two-point global line): x and y per series.
        [k_csv] = glob.glob(os.path.join(rep, "figures", "*-k-nominal-geometry.csv"))
        with open(k_csv) as f:
            rows = list(csv.reader(f))
        self.assertEqual(rows[0], ["instantaneous: t (s)", "instantaneous (N/m)", "sliding window: t (s)",
                                   "sliding window (N/m)", "global: t (s)", "global (N/m)"])
        self.assertEqual(sum(1 for row in rows[1:] if row[5] != ""), 2)
        self.assertAlmostEqual(float(rows[1][5]), d["nominal"]["K"], delta=1e-9 * d["nominal"]["K"])
        out = os.path.join(self.dir, "c.json")
        r = hil("contact", "identify", RUN, "--geometric", "--lcurve-points", "4", "--json", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("K", r.stdout)
        with open(out) as f:
            d = self.check("contact_identification", json.load(f))
        self.assertIn("l_curve", d)
        self.assertIn("observability", d)

    def test_hidden_effects(self):
        r = hil("contact", "simulate", "--rig", RIG, "--trajectory", TRAJ, "--out", os.path.join(self.dir, "sim"),
                "--inject", "sensor_bias", "--effect-seed", "4", "--truth-out", "-")
        d = self.check("hidden_effects", self.stdout_json(r))
        self.assertEqual(d["effects"], ["sensor_bias"])
        self.assertIn("wrote run", r.stderr)
        # Every injectable effect at once: each writes its own fields, all in the schema.
        effects = schema("hidden_effects")["properties"]["effects"]["items"]["enum"]
        r = hil("contact", "simulate", "--rig", RIG, "--trajectory", TRAJ, "--out", os.path.join(self.dir, "all"),
                "--inject", ",".join(effects), "--effect-seed", "4", "--truth-out", "-")
        d = self.check("hidden_effects", self.stdout_json(r))
        self.assertEqual(d["effects"], effects)
        self.assertNotEqual(d["time_offset_s"], 0)
        self.assertNotEqual(d["compliance"][0][0], 0)

    def test_the_hidden_effects_schema_is_the_effect_registrys(self):
        # docs/schemas/hil.hidden_effects.schema.json is what `hil contact truth-schema` makes from the
        # effect registry (regenerate: hil contact truth-schema --out docs/schemas/hil.hidden_effects.schema.json).
        r = hil("contact", "truth-schema")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(json.loads(r.stdout), schema("hidden_effects"))

    def test_stiffness_model_round_trip_and_wrong_kinds(self):
        r = hil("stiffness", "identify", TABLE, "--rig", KR_RIG, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5",
                "--json", "-")
        d = self.check("stiffness_model", self.stdout_json(r))
        self.assertEqual(d["rank"], len(d["parameters"]))
        self.assertIn("M4a", r.stderr)  # the text report went to stderr
        # A URDF robot's model, with its joint origins, axes and a mimic joint, fits the schema too.
        r = hil("stiffness", "identify", TABLE, "--rig", os.path.join(EX, "stiffness", "kr270_like_urdf.yaml"), "--json", "-")
        self.assertEqual(self.check("stiffness_model", self.stdout_json(r))["robot"]["convention"], "urdf")
        pal = os.path.join(EX, "robots", "palletizer_mimic.yaml")
        table = os.path.join(self.dir, "pal.csv")
        truth = os.path.join(self.dir, "truth.json")
        with open(truth, "w") as f:
            json.dump({"format": "hil-stiffness-model", "version": 1, "springs": {"J%d" % i: 1e-6 * i for i in range(1, 6)}}, f)
        self.assertEqual(hil("stiffness", "simulate", "--rig", pal, "--truth", truth, "--configs", "30", "--out", table).returncode, 0)
        r = hil("stiffness", "identify", table, "--rig", pal, "--json", "-")
        self.assertEqual(self.check("stiffness_model", self.stdout_json(r))["robot"]["joints"][3]["mimic"]["joint"], "elbow")
        model = os.path.join(self.dir, "model.json")
        with open(model, "w") as f:
            json.dump(d, f)
        # The stdout model is a model; predict's --out - is stdout too.
        r = hil("stiffness", "predict", model, "--data", os.path.join(EX, "stiffness", "configs.csv"), "--out", "-")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(len(r.stdout.splitlines()), 4)
        # Another kind of hil JSON as a model: exit 2, naming the file, the field and the kind.
        wrong = os.path.join(self.dir, "validation.json")
        self.assertEqual(hil("validate", RIG, "--json", wrong).returncode, 0)
        r = hil("stiffness", "predict", wrong, "--data", os.path.join(EX, "stiffness", "configs.csv"))
        self.assertEqual(r.returncode, 2, r.stderr)
        for needle in ("validation.json", "'format'", "hil.validation", "hil.stiffness_model"):
            self.assertIn(needle, r.stderr)
        r = hil("stiffness", "worker", "--rig", KR_RIG, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5", "--model", wrong,
                "--timeout-s", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("hil.validation", r.stderr)
        # The worker needs an identify output: a file without a format is refused, naming it.
        bare = os.path.join(self.dir, "bare.json")
        with open(bare, "w") as f:
            json.dump({"parameters": [], "fixed": []}, f)
        r = hil("stiffness", "worker", "--rig", KR_RIG, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5", "--model", bare,
                "--timeout-s", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("bare.json", r.stderr)
        self.assertIn("format", r.stderr)
        # A negative estimate period is refused, naming the option.
        r = hil("stiffness", "worker", "--rig", KR_RIG, "--noise-pos-m", "1e-5", "--noise-rot-rad", "1e-5",
                "--estimate-period-ms", "-5", "--timeout-s", "1")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--estimate-period-ms", r.stderr)
        # A newer format_version than this hil reads.
        d["format_version"] = 2
        with open(model, "w") as f:
            json.dump(d, f)
        r = hil("stiffness", "predict", model, "--data", os.path.join(EX, "stiffness", "configs.csv"))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("format_version", r.stderr)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
