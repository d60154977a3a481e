#!/bin/sh
# The whole rig with a hidden effect (issue 6): a press-and-slide run simulated with a sensor bias
# drawn by seed is played by `hil fake-rig` on vcan0 (the ATI plate on a real CAN_RAW socket, the
# Modbus controller on 127.0.0.1), `hil acquire` records it, and `hil diagnose` must name the bias
# blind, with the drawn values inside its intervals.
# usage: vcan_diagnose.sh HIL SOURCE_DIR WORK_DIR
set -eu
HIL=$1 SRC=$2 WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
. "$SRC/tests/vm/fake-rig-session.sh"
slow_press_bench_rig
"$HIL" contact simulate --rig "$WORK/rig.yaml" --trajectory "$SRC/examples/trajectories/press_slide.csv" \
  --out "$WORK/played" --force-resolution 0.05 --force-noise 0.1 --moment-resolution 0.002 --moment-noise 0.005 \
  --seed 4 --inject sensor_bias --effect-seed 4 --truth-out "$WORK/truth.json" > "$WORK/simulate.log"
PORT=${HIL_FAKE_PORT:-15021}
start_fake_rig "$WORK/played" $PORT
acquire_from_fake_rig $PORT "${HIL_DDS_DOMAIN:-172}"
kill $FR; wait $FR 2>/dev/null || true
"$HIL" diagnose "$WORK/run" --json "$WORK/diagnosis.json" --quiet > "$WORK/diagnosis.txt" ||
  { echo "hil diagnose failed"; cat "$WORK/diagnosis.txt"; exit 1; }
/usr/bin/python3 - "$WORK" <<'PY'
import json, sys
work = sys.argv[1]
with open(work + "/truth.json") as f:
    truth = json.load(f)
with open(work + "/diagnosis.json") as f:
    d = json.load(f)
summary = open(work + "/diagnosis.txt").read()
assert d["cause"]["name"] == "sensor_bias", "named %s, not sensor_bias:\n%s" % (d["cause"]["name"], summary)
assert d["gain_percent"] > 0, summary
# The drawn offsets against the estimates. The acquisition chain is not the simulation: its
# anti-aliasing filter smooths the wrench at the contact transitions and the twist comes from
# filtered differences of a 125 Hz pose, so the estimates carry a systematic error the statistical
# interval does not cover. The run slides along x: the friction signal is distorted most (mu ~0.17
# against 0.20 on a clean run, docs/diagnosis.md), which leaks into the fx and my offsets: those
# within 30 %; the others within 3 std or 10 % (a fresh-clone CI run saw fz 4.4 % = 3.06 std off).
for i, c in enumerate(["fx", "fy", "fz", "mx", "my", "mz"]):
    p = d["cause"]["parameters"]["bias_" + c]
    t = truth["sensor_bias"][i]
    tol = 0.3 * abs(t) if c in ("fx", "my") else max(3 * p["std"], 0.1 * abs(t))
    assert abs(p["value"] - t) <= tol, (c, p, t, summary)
print("vcan diagnose: %d samples, cause %s, gain %.1f %%" % (d["samples"], d["cause"]["name"], d["gain_percent"]))
PY
