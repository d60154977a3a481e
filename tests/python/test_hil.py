"""The `hil` Python module (docs/python.md): readers checked against Python's own csv module,
rig reading, errors naming file and line, contact identification against the simulation's truth
and the `hil` command, a blind diagnosis of a hidden effect simulated by the command, the
elastostatic calibration, and the GIL released while C++ computes.

Run by ctest (tests/python/CMakeLists.txt) with PYTHONPATH=<build>/python, HIL_SOURCE_DIR and HIL_EXE."""
import csv
import json
import math
import os
import shutil
import subprocess
import threading
import time

import numpy as np
import pytest

import hil

SRC = os.environ.get("HIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
HIL_EXE = os.environ.get("HIL_EXE", "")
RUN = os.path.join(SRC, "examples", "runs", "press_slide")
RIG = os.path.join(SRC, "examples", "rigs", "press_bench.yaml")
TRAJ = os.path.join(SRC, "examples", "trajectories", "press_slide.csv")
STIFF_RIG = os.path.join(SRC, "examples", "stiffness", "kr270_like.yaml")
STIFF_TABLE = os.path.join(SRC, "examples", "stiffness", "table.csv")

needs_cli = pytest.mark.skipif(not os.access(HIL_EXE, os.X_OK), reason="HIL_EXE (the hil command) not given")


def csv_columns(path):
    """samples.csv read by Python's csv module: column name -> list of floats."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header, data = rows[0], rows[1:]
    return {name: [float(r[i]) for r in data] for i, name in enumerate(header)}


def test_read_run_equals_the_csv():
    run = hil.read_run(RUN)
    cols = csv_columns(os.path.join(RUN, "samples.csv"))
    n = len(cols["t"])
    assert n == 325
    assert run["t"].shape == (n,)
    np.testing.assert_array_equal(run["t"], cols["t"])
    for key, names in {"p": "px py pz", "q": "qw qx qy qz", "v": "vx vy vz", "w": "wx wy wz", "f": "fx fy fz",
                       "m": "mx my mz"}.items():
        expected = np.column_stack([cols[c] for c in names.split()])
        assert run[key].shape == expected.shape, key
        if key == "q":  # the reader normalises the quaternion (within its 1e-6 tolerance)
            np.testing.assert_allclose(run[key], expected, rtol=0, atol=1e-9)
        else:
            np.testing.assert_array_equal(run[key], expected, key)
    assert run["joints"].shape == (n, 0) and run["joint_names"] == []
    assert run["extra"] == {}
    assert run["line"][0] == 2 and run["line"][-1] == n + 1  # line 1 is the header
    meta = run["meta"]
    assert meta["rig"] == "press_bench"
    assert meta["output_rate_hz"] == 50
    assert meta["start_time"] == "2026-01-01T00:00:00.000Z"
    assert meta["sources"][0]["kind"] == "simulation" and meta["sources"][0]["rate_hz"] == 50
    assert "press_slide.csv" in meta["notes"]
    assert run["rig"]["name"] == "press_bench"  # the run's rig.yaml


def test_joints_and_extra_columns(tmp_path):
    path = tmp_path / "samples.csv"
    path.write_text("t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,mx,my,mz,j2,j1,quality,label\n"
                    "0,1,2,3,1,0,0,0,0,0,0,0,0,0,4,5,6,7,8,9,0.5,-0.25,0,a\n"
                    "# a comment line\n"
                    "0.01,1,2,3,0,1,0,0,0,0,0,0,0,0,4,5,6,7,8,9,0.75,-0.5,3,b\n")
    s = hil.read_samples(path)  # a pathlib.Path, as any os.PathLike
    np.testing.assert_array_equal(s["joints"], [[-0.25, 0.5], [-0.5, 0.75]])  # j1 first, whatever the file order
    assert s["joint_names"] == ["j1", "j2"]
    np.testing.assert_array_equal(s["extra"]["quality"], [0.0, 3.0])
    assert s["extra"]["label"] == ["a", "b"]
    np.testing.assert_array_equal(s["q"][1], [0, 1, 0, 0])
    np.testing.assert_array_equal(s["line"], [2, 4])
    assert s["columns"][-4:] == ["j1", "j2", "quality", "label"]


def test_read_rig():
    rig = hil.read_rig(RIG)
    assert rig["name"] == "press_bench"
    frames = {f["name"]: f for f in rig["frames"]}
    assert set(frames) == {"force_plate", "object2", "object1"}
    assert frames["object2"]["parent"] == "force_plate"
    assert rig["tf"] == {"world": "world", "base": "robot_base", "ee": "ee"}
    np.testing.assert_array_equal(frames["object2"]["T_parent_frame"]["translation_m"], [0, 0, 0.05])
    np.testing.assert_array_equal(frames["object2"]["T_parent_frame"]["matrix"][:3, 3], [0, 0, 0.05])
    robot = rig["robot"]
    assert robot["name"] == "ur5e" and robot["convention"] == "standard"
    assert robot["dh"].shape == (6, 4) and robot["dh_columns"][0] == "a_m"
    np.testing.assert_array_equal(robot["dh"][:, 0], [0.0, -0.425, -0.3922, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(robot["dh"][:, 2], [0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996])
    np.testing.assert_array_equal(robot["limits"][2], [-3.1416, 3.1416])
    np.testing.assert_array_equal(robot["T_world_base"]["translation_m"], [-0.45, 0, 0])
    objects = {o["name"]: o for o in rig["objects"]}
    cube = objects["cube"]["features"][0]["polyhedra"][0]
    assert objects["cube"]["frame"] == "object1" and cube.shape == (8, 3)
    np.testing.assert_array_equal(cube[6], [0.015, 0.015, 0.03])
    assert objects["block"]["features"][0]["name"] == "top"
    contact = rig["model"]["contact"]
    assert contact["stiffness_n_per_m"] == 1.8e5 and contact["friction_coefficient"] == 0.2
    unc = rig["model"]["uncertainties"]
    assert [u["name"] for u in unc] == ["block_top_z", "block_tilt_x"]
    assert unc[1]["kind"] == "rotation" and unc[1]["prior_std"] == 1e-3
    np.testing.assert_array_equal(unc[0]["axis"], [0, 0, 1])
    fp, robot_dev = rig["devices"]["force_plate"], rig["devices"]["robot"]
    assert fp["protocol"] == "ati_netcanoem" and fp["base_id"] == 0
    np.testing.assert_array_equal(fp["saturation_limits"], [660, 660, 1980, 60, 60, 60])
    assert fp["gain_tolerance"] == 0.15
    assert robot_dev["port"] == 5020 and robot_dev["register_map"] == "ur"


def test_a_urdf_robot_reads_and_identifies_as_its_dh_table():
    urdf_rig = os.path.join(SRC, "examples", "stiffness", "kr270_like_urdf.yaml")
    robot = hil.read_rig(urdf_rig)["robot"]
    assert robot["convention"] == "urdf"
    assert (robot["base_link"], robot["tip_link"]) == ("base_link", "tool0")
    assert robot["urdf"].endswith("kr270_like.urdf")
    assert robot["body_links"] == ["base_link"] + ["link_%d" % i for i in range(1, 7)]
    assert [j["name"] for j in robot["joints"]] == ["a1", "a2", "a3", "a4", "a5", "a6"]
    np.testing.assert_allclose(robot["joints"][1]["T_parent_joint"]["translation_m"], [0.35, 0, 0.675])
    np.testing.assert_array_equal(robot["joints"][1]["axis"], [0, 0, 1])
    a, b = hil.identify_stiffness(STIFF_TABLE, STIFF_RIG), hil.identify_stiffness(STIFF_TABLE, urdf_rig)
    assert a["rank"] == b["rank"]
    va = {p["name"]: p["value"] for p in a["parameters"]}
    vb = {p["name"]: p["value"] for p in b["parameters"]}
    assert va.keys() == vb.keys()
    for k in va:
        assert vb[k] == pytest.approx(va[k], rel=1e-6), k
    # A mimic joint says whom it follows; independent joints have no "mimic" entry.
    pal = hil.read_rig(os.path.join(SRC, "examples", "robots", "palletizer_mimic.yaml"))["robot"]
    assert pal["joints"][3]["mimic"] == {"joint": "elbow", "multiplier": -1.0, "offset": 0.0}
    assert all("mimic" not in j for i, j in enumerate(pal["joints"]) if i != 3)
    # A URDF robot's base is its base link on /tf.
    assert hil.read_rig(os.path.join(SRC, "examples", "robots", "palletizer_mimic.yaml"))["tf"]["base"] == "base_link"


@needs_cli
def test_calibrate_a_real_calibration_run(tmp_path):
    data = os.path.join(SRC, "..", "shared", "data", "ur10-calibration", "calibration.csv")
    if not os.path.exists(data):
        pytest.skip("the shared UR10 data is not beside the clone")
    rig = os.path.join(SRC, "examples", "robots", "ur10_rig.yaml")
    run = str(tmp_path / "ur10.csv")
    p = subprocess.run([HIL_EXE, "import", data, "--config", os.path.join(SRC, "examples", "import", "ur10_calibration.yaml"),
                        "--rig", rig, "--out", run], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    d = hil.calibrate(run, rig, candidates=["joint_offsets"], folds=4)
    assert d["format"] == "hil.point_calibration"
    assert d["rigid"]["rms_m"] == pytest.approx(10.865e-3, abs=5e-5)
    assert [h["model"] for h in d["held_out"]] == ["rigid", "joint_offsets"]
    with pytest.raises(ValueError, match="unknown candidate 'tilt'"):
        hil.calibrate(run, rig, candidates=["tilt"])
    d = hil.calibrate(run, rig, candidates=["link_bending"], folds=4, bending_links=["upper_arm_link"])
    assert d["bending_links"] + [x.split(" ")[1] for x in d["bending_dropped"]] == ["upper_arm_link"]
    with pytest.raises(ValueError, match="bending link 'forearm' is not a link"):
        hil.calibrate(run, rig, candidates=["link_bending"], bending_links=["forearm"])


def test_run_sources_keep_the_device_identity(tmp_path):
    shutil.copytree(RUN, tmp_path / "run")
    (tmp_path / "run" / "run.yaml").write_text(
        "format_version: 1\nrig: press_bench\nstart_time: 2026-11-21T09:00:00.000Z\noutput_rate_hz: 50\n"
        "sources:\n"
        "  - {name: force_plate, kind: can, rate_hz: 1000, identity: {serial: FT12345, firmware: '2.1'}}\n"
        "  - {name: robot, kind: modbus, rate_hz: 125}\n")
    meta = hil.read_run(str(tmp_path / "run"))["meta"]
    assert meta["sources"][0]["identity"] == {"serial": "FT12345", "firmware": "2.1"}
    assert list(meta["sources"][0]["identity"]) == ["serial", "firmware"]
    assert meta["sources"][1]["identity"] == {} and meta["sources"][1]["raw"] == ""
    assert meta["notes"] == ""


def test_bad_cell_names_file_line_and_column(tmp_path):
    shutil.copytree(RUN, tmp_path / "run")
    path = tmp_path / "run" / "samples.csv"
    lines = path.read_text().splitlines(keepends=True)
    header = lines[0].strip().split(",")
    cells = lines[4].strip().split(",")
    cells[header.index("fz")] = "1.2.3"
    lines[4] = ",".join(cells) + "\n"
    path.write_text("".join(lines))
    with pytest.raises(hil.FormatError) as e:
        hil.read_run(tmp_path / "run")
    msg = str(e.value)
    assert str(path) in msg and ":5:" in msg and "fz" in msg, msg
    assert isinstance(e.value, ValueError)
    assert e.value.file == str(path) and e.value.line == 5 and e.value.field == "fz"
    assert e.value.column == header.index("fz") + 1


def test_bad_rig_key_names_line_and_the_closest_field(tmp_path):
    text = open(RIG).read().replace("stiffness_n_per_m:", "stifness_n_per_m:")
    line = next(i + 1 for i, l in enumerate(text.splitlines()) if "stifness_n_per_m" in l)
    path = tmp_path / "rig.yaml"
    path.write_text(text)
    with pytest.raises(ValueError) as e:
        hil.read_rig(str(path))
    msg = str(e.value)
    assert f"{path}:{line}:" in msg and "stiffness_n_per_m" in msg, msg


def test_missing_file_is_reported():
    with pytest.raises(hil.FormatError, match="no_such_run"):
        hil.read_run(os.path.join(SRC, "no_such_run"))


def test_identify_contact_finds_the_simulated_truth():
    r = hil.identify_contact(RUN)
    truth_K, truth_mu = 1.8e5, 0.2  # the rig's model, which simulated the run (run.yaml notes)
    lo, hi = r["K_ci95"]
    assert lo < r["K"] < hi and hi - lo == pytest.approx(2 * 1.959963984540054 * r["K_std"])
    assert abs(r["K"] - truth_K) < 0.03 * truth_K
    assert abs(r["K"] - truth_K) < 5 * r["K_std"]
    assert r["mu_identifiable"]
    assert abs(r["mu"] - truth_mu) < 0.02
    lo, hi = r["mu_ci95"]
    assert lo < r["mu"] < hi
    assert r["rank"] == 2 and math.isfinite(r["condition"])
    assert 0 < r["samples_in_contact"] < r["samples"] == 325
    assert r["relative_force_error"] == r["nominal"]["relative_force_error"]  # no geometry fitted
    # The fit, per sample in contact: the measured wrench is the run's, the model explains it.
    run = hil.read_run(RUN)
    fit = r["fit"]
    k = fit["sample"]
    assert len(k) == r["samples_in_contact"]
    np.testing.assert_array_equal(fit["t"], run["t"][k])
    np.testing.assert_array_equal(fit["measured_fp"], np.hstack([run["f"], run["m"]])[k])
    np.testing.assert_allclose(fit["residual_fp"], fit["measured_fp"] - fit["model_fp"], atol=1e-12)
    fz, res_fz = fit["measured_fp"][:, 2], fit["residual_fp"][:, 2]
    assert np.sqrt(np.mean(res_fz ** 2)) < 0.05 * np.sqrt(np.mean(fz ** 2))
    assert np.all(fit["contacts"] > 0)
    K_window = r["window"]["K"][np.isfinite(r["window"]["K"])]
    assert len(K_window) > 0 and abs(np.median(K_window) - truth_K) < 0.1 * truth_K


@needs_cli
def test_bad_keyword_values_raise_value_error_naming_the_keyword():
    for kwargs, name in (({"solver": "newton"}, "solver"), ({"solver": "newton", "geometric": True}, "solver"),
                         ({"jacobian": "exact"}, "jacobian"), ({"lambda_": "-1"}, "lambda_"), ({"lambda_": "big"}, "lambda_"),
                         ({"window": 0}, "window")):
        with pytest.raises(ValueError, match=name) as e:
            hil.identify_contact(RUN, **kwargs)
        assert "--" not in str(e.value), str(e.value)  # the Python keyword, not a CLI flag
    with pytest.raises(ValueError, match="candidates: 'magnetism' is not a candidate here") as e:
        hil.diagnose(RUN, candidates=["magnetism"])
    assert "--" not in str(e.value), str(e.value)


def test_identify_contact_agrees_with_the_command(tmp_path):
    out = tmp_path / "id.json"
    p = subprocess.run([HIL_EXE, "contact", "identify", RUN, "--json", str(out)], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    cli = json.loads(out.read_text())
    r = hil.identify_contact(RUN)
    for key in ("K", "K_std", "mu", "mu_std", "rank", "condition", "samples_in_contact", "relative_force_error"):
        assert r[key] == pytest.approx(cli[key], rel=1e-12), key


def test_simulate_contact_reproduces_the_shipped_run():
    # examples/runs/press_slide was written by `hil contact simulate` with these settings (its notes).
    notes = hil.read_run(RUN)["meta"]["notes"]
    assert "position resolution 2e-06 m, velocity resolution 0.0002 m/s, force resolution 0.05 N (noise 0.1 N)" in notes
    assert "moment resolution 0.001 N m (noise 0.005 N m), seed 7" in notes
    s = hil.simulate_contact(RIG, TRAJ, position_resolution_m=2e-6, velocity_resolution_m_per_s=2e-4,
                             force_resolution_n=0.05, force_noise_n=0.1, moment_resolution_nm=0.001,
                             moment_noise_nm=0.005, seed=7)
    run = hil.read_run(RUN)
    for key in ("t", "p", "q", "v", "w", "f", "m"):
        np.testing.assert_array_equal(s[key], run[key], key)
    assert s["K"] == 1.8e5 and s["mu"] == 0.2
    # The identification finds contact on the measured (quantised) poses: a borderline sample may differ.
    assert abs(np.count_nonzero(s["contacts"]) - hil.identify_contact(RUN)["samples_in_contact"]) <= 2
    assert 0 < np.max(np.abs(s["f"] - s["f_true"])) < 0.05 + 6 * 0.1


def test_simulate_contact_force_scales_with_the_stiffness():
    # Surface compliance: the motion is given, so the wrench is proportional to K (same contacts).
    a = hil.simulate_contact(RIG, TRAJ)
    b = hil.simulate_contact(RIG, TRAJ, K=3.6e5)
    assert np.max(np.abs(a["f_true"][:, 2])) > 10
    np.testing.assert_allclose(b["f_true"], 2 * a["f_true"], rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(a["f"], a["f_true"])  # no sensor model: measured = true
    c = hil.simulate_contact(RIG, TRAJ, geometric={"block_top_z": 1e-4})  # the top face 0.1 mm higher
    assert np.max(np.abs(c["f_true"][:, 2])) > np.max(np.abs(a["f_true"][:, 2]))
    with pytest.raises(ValueError, match="K"):
        hil.simulate_contact(RIG, TRAJ, K=-1.0)
    with pytest.raises(ValueError, match="geometric: unknown geometric uncertainty 'no_such_offset'"):
        hil.simulate_contact(RIG, TRAJ, geometric={"no_such_offset": 1e-4})
    with pytest.raises(hil.FormatError, match="trajectory.csv"):
        hil.simulate_contact(RIG, os.path.join(SRC, "no_such", "trajectory.csv"))


@needs_cli
def test_diagnose_names_a_hidden_sensor_bias(tmp_path):
    run = tmp_path / "bias"
    truth_path = tmp_path / "truth.json"
    p = subprocess.run([HIL_EXE, "contact", "simulate", "--rig", RIG, "--trajectory", TRAJ, "--out", str(run),
                        "--force-resolution", "0.1", "--force-noise", "0.1", "--moment-resolution", "0.005",
                        "--moment-noise", "0.005", "--seed", "3", "--inject", "sensor_bias", "--effect-seed", "5",
                        "--truth-out", str(truth_path)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    truth = json.loads(truth_path.read_text())
    d = hil.diagnose(str(run), candidates=["sensor_bias", "sensor_gain", "viscous_friction"])
    assert d["mode"] == "contact"
    assert d["cause"]["name"] == "sensor_bias"
    assert d["second_cause"] is None
    assert d["gain_percent"] > 50
    assert d["extended"]["relative_error"] < d["nominal"]["relative_error"]
    assert {c["name"] for c in d["candidates"]} == {"sensor_bias", "sensor_gain", "viscous_friction"}
    for i, c in enumerate(["fx", "fy", "fz", "mx", "my", "mz"]):
        par = d["cause"]["parameters"]["bias_" + c]
        assert abs(par["value"] - truth["sensor_bias"][i]) <= 3 * par["std"], c
    out = tmp_path / "d.json"
    p = subprocess.run([HIL_EXE, "diagnose", str(run), "--candidates", "sensor_bias,sensor_gain,viscous_friction",
                        "--json", str(out), "--quiet"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    cli = json.loads(out.read_text())
    assert cli["cause"]["name"] == d["cause"]["name"]
    assert cli["gain_percent"] == pytest.approx(d["gain_percent"], rel=1e-9)
    assert [c["verdict"] for c in cli["candidates"]] == [c["verdict"] for c in d["candidates"]]
    with pytest.raises(ValueError, match="candidates: 'not_a_cause'"):
        hil.diagnose(str(run), candidates=["not_a_cause"])
    with pytest.raises(ValueError, match="folds"):
        hil.diagnose(str(run), folds=1)
    with pytest.raises(ValueError, match="cv_offsets: must be 0"):
        hil.diagnose(str(run), cv_offsets=-1)


def test_diagnose_progress_and_stopping_it():
    seen = []
    d = hil.diagnose(RUN, candidates=["sensor_bias", "sensor_gain"], progress=lambda *a: seen.append(a))
    assert d["cause"]["name"] == "none"  # the run is the rig's own model with sensor noise
    total = seen[0][1]  # the nominal model, each candidate, the second-step pairs the engine allows
    assert seen[0] == (1, total, "nominal") and total >= 3
    assert [s[2] for s in seen[1:3]] == ["sensor_bias", "sensor_gain"]
    assert [s[0] for s in seen] == sorted(s[0] for s in seen) and seen[-1][:2] == (total, total)

    class Stop(Exception):
        pass

    def stop_at_the_second_step(step, total, what):
        if step == 2:
            raise Stop(what)

    with pytest.raises(Stop, match="sensor_bias"):  # the callback's own exception, unchanged
        hil.diagnose(RUN, candidates=["sensor_bias", "sensor_gain"], progress=stop_at_the_second_step)
    with pytest.raises(TypeError, match="progress"):
        hil.diagnose(RUN, progress=3)


def test_diagnose_a_stiffness_table():
    # The shipped table's robot has compliant links the joint-compliance model lacks.
    d = hil.diagnose(STIFF_TABLE, rig=STIFF_RIG)
    assert d["mode"] == "stiffness"
    assert d["cause"]["name"] == "link_compliance"
    assert d["gain_percent"] > 10
    with pytest.raises(hil.FormatError, match="needs --rig"):
        hil.diagnose(STIFF_TABLE)


def test_identify_stiffness_on_the_shipped_table():
    # The table was simulated with noise of std 1e-5 m / 1e-5 rad per axis (its first line): the
    # identified model leaves residuals at that level, and the reduction keeps 20 parameters
    # (docs/calibration.md).
    with open(STIFF_TABLE) as f:
        assert "noise σ 1e-05 m / 1e-05 rad" in f.readline()
    r = hil.identify_stiffness(STIFF_TABLE, STIFF_RIG)
    assert r["rank"] == len(r["parameters"]) == 20
    for axis in ("dx", "dy", "dz", "rx", "ry", "rz"):
        assert 0.7e-5 < r["residual_rms"][axis] < 1.4e-5, (axis, r["residual_rms"])
    assert r["noise"]["estimated"] and 0.7e-5 < r["noise"]["position_m"] < 1.4e-5
    for p in r["parameters"]:
        lo, hi = p["ci95"]
        assert lo < p["value"] < hi, p
        assert p["std"] > 0 and p["pnr"] >= 2  # M6 neglects those below 2
    names = [p["name"] for p in hil.identify_stiffness(STIFF_TABLE, STIFF_RIG, neglect_below=0)["parameters"]]
    assert len(names) > 20  # without M6, the weak parameters stay


@needs_cli
def test_identify_stiffness_agrees_with_the_command(tmp_path):
    out = tmp_path / "model.json"
    p = subprocess.run([HIL_EXE, "stiffness", "identify", STIFF_TABLE, "--rig", STIFF_RIG, "--json", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    cli = json.loads(out.read_text())
    r = hil.identify_stiffness(STIFF_TABLE, STIFF_RIG)
    assert [q["name"] for q in r["parameters"]] == [q["name"] for q in cli["parameters"]]
    for a, b in zip(r["parameters"], cli["parameters"]):
        assert a["value"] == pytest.approx(b["value"], rel=1e-9), a["name"]


def test_identify_stiffness_bad_table(tmp_path):
    path = tmp_path / "table.csv"
    lines = open(STIFF_TABLE).read().splitlines(keepends=True)
    path.write_text("".join(lines[:3]) + lines[3].replace(",", ",x", 1) + "".join(lines[4:]))
    with pytest.raises(hil.FormatError) as e:
        hil.identify_stiffness(str(path), STIFF_RIG)
    assert e.value.line == 4 and str(path) in str(e.value)


def test_the_gil_is_released_while_identifying():
    # The main thread stamps the clock every millisecond while a second thread identifies: stamps
    # fall inside the call only if the call let go of the GIL.
    stamps, seen = [], {}
    done = threading.Event()

    def work():
        seen["t0"] = time.monotonic()
        seen["result"] = hil.identify_contact(RUN, geometric=True, lcurve_points=100)
        seen["t1"] = time.monotonic()
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    while not done.is_set():
        stamps.append(time.monotonic())
        time.sleep(0.001)
    thread.join()
    assert seen["result"]["geometric"]
    t0, t1 = seen["t0"], seen["t1"]
    assert t1 - t0 > 0.1, "the call is too short to tell"
    inside = [t for t in stamps if t0 + 0.25 * (t1 - t0) < t < t1 - 0.25 * (t1 - t0)]
    assert len(inside) >= 10, (len(inside), t1 - t0)
