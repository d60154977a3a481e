#!/bin/sh
# In the vcan guest (or on a host with SocketCAN), three processes: `hil fake-rig` plays the
# example run (ATI plate on vcan0, Modbus controller on 127.0.0.1), `hil acquire` polls both
# through a real CAN_RAW socket with kernel timestamps and libmodbus, and candump -L watches the
# bus. The recorded run must be valid and carry the played wrench.
# usage: vcan_acquire.sh HIL SOURCE_DIR WORK_DIR
set -eu
HIL=$1 SRC=$2 WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
# The guest emulates the CPU (TCG, 10-15x slower): poll the plate at 200 Hz instead of the rig's
# 1 kHz so that request/response keeps up; everything else is the shipped rig.
sed 's/^    rate_hz: 1000$/    rate_hz: 200/' "$SRC/examples/rigs/press_bench.yaml" > "$WORK/rig.yaml"
grep -q "rate_hz: 200" "$WORK/rig.yaml" || { echo "could not set the plate rate"; exit 1; }
candump -L vcan0 > "$WORK/candump.log" &
CD=$!
sleep 0.3
PORT=${HIL_FAKE_PORT:-15020}
"$HIL" fake-rig --rig "$WORK/rig.yaml" --run "$SRC/examples/runs/press_slide" --loop \
  --can vcan0 --port $PORT > "$WORK/fake-rig.log" 2>&1 &
FR=$!
# The guest is slow (TCG): wait until the fake rig says it is serving, at most 30 s.
i=0
until grep -q "robot controller Modbus" "$WORK/fake-rig.log" 2>/dev/null; do
  i=$((i + 1)); [ $i -le 300 ] || { echo "fake-rig did not start"; cat "$WORK/fake-rig.log"; exit 1; }
  sleep 0.1
done
sleep 0.5
HIL_DDS_DOMAIN=${HIL_DDS_DOMAIN:-171} "$HIL" acquire --rig "$WORK/rig.yaml" --out "$WORK/run" \
  --can-interface vcan0 --robot-port $PORT --duration 6.5 > "$WORK/acquire.log" 2>&1 ||
  { echo "hil acquire failed:"; cat "$WORK/acquire.log"; echo "fake-rig:"; cat "$WORK/fake-rig.log"; exit 1; }
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
