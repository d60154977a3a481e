# Sourced by the whole-rig vcan tests (tests/acquisition/vcan_acquire.sh,
# tests/diagnosis/vcan_diagnose.sh): the press bench rig slowed for the guest, `hil fake-rig` on
# vcan0 + 127.0.0.1, and `hil acquire` recording from it. Expects HIL, SRC and WORK to be set.

# $WORK/rig.yaml: the shipped press bench with the plate polled at 200 Hz instead of 1 kHz: the
# guest emulates the CPU (TCG, 10-15x slower) and request/response must keep up.
slow_press_bench_rig() {
  sed 's/^    rate_hz: 1000$/    rate_hz: 200/' "$SRC/examples/rigs/press_bench.yaml" > "$WORK/rig.yaml"
  grep -q "rate_hz: 200" "$WORK/rig.yaml" || { echo "could not set the plate rate"; exit 1; }
}

# start_fake_rig RUN PORT: plays RUN in a loop (ATI plate on vcan0, Modbus controller on
# 127.0.0.1:PORT); sets FR to its pid once it says it is serving (at most 30 s: the guest is slow).
start_fake_rig() {
  "$HIL" fake-rig --rig "$WORK/rig.yaml" --run "$1" --loop --can vcan0 --port "$2" > "$WORK/fake-rig.log" 2>&1 &
  FR=$!
  i=0
  until grep -q "robot controller Modbus" "$WORK/fake-rig.log" 2>/dev/null; do
    i=$((i + 1)); [ $i -le 300 ] || { echo "fake-rig did not start"; cat "$WORK/fake-rig.log"; exit 1; }
    sleep 0.1
  done
  sleep 0.5
}

# acquire_from_fake_rig PORT DDS_DOMAIN: 6.5 s of `hil acquire` into $WORK/run through a real
# CAN_RAW socket and libmodbus; on failure prints both logs and exits.
acquire_from_fake_rig() {
  HIL_DDS_DOMAIN=$2 "$HIL" acquire --rig "$WORK/rig.yaml" --out "$WORK/run" \
    --can-interface vcan0 --robot-port "$1" --duration 6.5 > "$WORK/acquire.log" 2>&1 ||
    { echo "hil acquire failed:"; cat "$WORK/acquire.log"; echo "fake-rig:"; cat "$WORK/fake-rig.log"; exit 1; }
}
