#!/bin/sh
# In the vcan guest (or on a host with SocketCAN), three processes: `hil fake-rig` plays the
# example run (ATI plate on vcan0, Modbus controller on 127.0.0.1), `hil acquire` polls both
# through a real CAN_RAW socket with kernel timestamps and libmodbus, and candump -L watches the
# bus. The recorded run must be valid and carry the played wrench.
# usage: vcan_acquire.sh HIL SOURCE_DIR WORK_DIR
set -eu
HIL=$1 SRC=$2 WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
. "$SRC/tests/vm/fake-rig-session.sh"
slow_press_bench_rig
candump -L vcan0 > "$WORK/candump.log" &
CD=$!
sleep 0.3
PORT=${HIL_FAKE_PORT:-15020}
start_fake_rig "$SRC/examples/runs/press_slide" $PORT
# The bring-up check (docs/hardware.md) against the separate fake-rig process, over vcan0.
"$HIL" acquire --rig "$WORK/rig.yaml" --can-interface vcan0 --robot-port $PORT --check > "$WORK/check.txt" 2>&1 ||
  { echo "hil acquire --check failed:"; cat "$WORK/check.txt"; cat "$WORK/fake-rig.log"; exit 1; }
grep -q "serial *FT-FAKE1" "$WORK/check.txt" && grep -q "on vcan0" "$WORK/check.txt" && grep -q "check passed" "$WORK/check.txt" ||
  { echo "hil acquire --check did not print the plate's identity on vcan0:"; cat "$WORK/check.txt"; exit 1; }
acquire_from_fake_rig $PORT "${HIL_DDS_DOMAIN:-171}"
kill $FR $CD; wait $FR 2>/dev/null || true; wait $CD 2>/dev/null || true
"$HIL" validate "$WORK/run" > "$WORK/validate.txt"
/usr/bin/python3 - "$WORK" "$SRC" <<'PY'
import csv, sys
work = sys.argv[1]
rows = list(csv.DictReader(open(work + "/run/samples.csv")))
assert len(rows) >= 100, "only %d samples recorded in 6.5 s at 50 Hz" % len(rows)
fz = min(float(r["fz"]) for r in rows)
played = min(float(r["fz"]) for r in csv.DictReader(open(sys.argv[2] + "/examples/runs/press_slide/samples.csv")))
assert abs(fz - played) < 5.0, "peak fz %.2f, played %.2f" % (fz, played)
log = open(work + "/candump.log").read().split("\n")
req = [l for l in log if l.endswith(" vcan0 000#")]  # ATI gauge requests: id base << 4 | 0x0, no data
ans = [l for l in log if " vcan0 001#" in l]         # the second frame of each answer (SG1, SG3, SG5)
assert len(req) > 100 and len(ans) > 100, "candump saw %d requests, %d answers" % (len(req), len(ans))
raw = list(csv.DictReader(open(work + "/run/raw/force_plate.csv")))
assert any(r["stamp"] != "0" for r in raw), "no kernel receive stamps"
print("vcan acquire: %d samples, peak fz %.2f N, %d requests and %d answers on vcan0" % (len(rows), fz, len(req), len(ans)))
PY
