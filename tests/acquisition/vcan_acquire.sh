#!/bin/sh
# In the vcan guest (or on a host with SocketCAN): the fake ATI plate answers on vcan0, hil
# acquire polls it through a real CAN_RAW socket with kernel timestamps, candump -L captures the
# traffic, and the recorded run must be valid and carry the played wrench.
# usage: vcan_acquire.sh HIL SOURCE_DIR WORK_DIR
set -eu
HIL=$1 SRC=$2 WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
candump -L vcan0 > "$WORK/candump.log" &
CD=$!
sleep 0.3
HIL_DDS_DOMAIN=${HIL_DDS_DOMAIN:-171} "$HIL" acquire --rig "$SRC/examples/rigs/press_bench.yaml" --out "$WORK/run" \
  --play "$SRC/examples/runs/press_slide" --play-on-can --can-interface vcan0 --play-speed 2
kill $CD; wait $CD 2>/dev/null || true
"$HIL" validate "$WORK/run" > "$WORK/validate.txt"
/usr/bin/python3 - "$WORK" <<'PY'
import csv, sys
work = sys.argv[1]
rows = list(csv.DictReader(open(work + "/run/samples.csv")))
assert len(rows) >= 80, "only %d samples recorded" % len(rows)
fz = min(float(r["fz"]) for r in rows)
assert abs(fz - (-360.2)) < 5.0, "peak fz %.2f, played -360.2" % fz
log = open(work + "/candump.log").read().split("\n")
req = [l for l in log if l.endswith(" vcan0 000#")]  # ATI gauge requests: id base << 4 | 0x0, no data
ans = [l for l in log if " vcan0 001#" in l]         # the second frame of each answer (SG1, SG3, SG5)
assert len(req) > 100 and len(ans) > 100, "candump saw %d requests, %d answers" % (len(req), len(ans))
raw = list(csv.DictReader(open(work + "/run/raw/force_plate.csv")))
assert any(r["stamp"] != "0" for r in raw), "no kernel receive stamps"
print("vcan acquire: %d samples, peak fz %.2f N, %d requests and %d answers on vcan0" % (len(rows), fz, len(req), len(ans)))
PY
