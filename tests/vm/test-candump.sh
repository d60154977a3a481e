#!/bin/bash
# vcan harness test (a), run inside the guest (or on a host with SocketCAN) by run-in-vm.sh:
# frames sent with can-utils' cansend on vcan0 are captured by `candump -L vcan0`: a classic
# frame, an extended-id RTR frame and two CAN FD frames (one with more than 8 data bytes, which
# needs the CAN FD MTU of 72 on vcan0). Also checks that vcan1 is up.
set -euo pipefail

fail() { echo "FAIL: $*" >&2; exit 1; }
for dev in vcan0 vcan1; do
  ip -details link show dev "$dev" | grep -qw vcan || fail "$dev is no vcan device"
  ip link show dev "$dev" | grep -q '[<,]UP[,>]' || fail "$dev is not up"
done
mtu=$(cat /sys/class/net/vcan0/mtu)
[[ $mtu == 72 ]] || fail "vcan0 mtu is $mtu, CAN FD needs 72"

log=$(mktemp)
dump=
trap 'kill "$dump" 2> /dev/null || true; rm -f "$log"' EXIT
rx_before=$(grep -c '^ *vcan0 ' /proc/net/can/rcvlist_all || true)
candump -L vcan0 > "$log" &
dump=$!
# Wait until candump's CAN_RAW socket is bound (a new receiver on vcan0), not a fixed sleep.
for _ in $(seq 200); do
  (( $(grep -c '^ *vcan0 ' /proc/net/can/rcvlist_all || true) > rx_before )) && break
  kill -0 "$dump" 2> /dev/null || fail "candump exited early"
  sleep 0.05
done

cansend vcan0 123#DEADBEEF
cansend vcan0 1ABCDEF0#R
cansend vcan0 456##1AABBCC
cansend vcan0 456##100112233445566778899AABB

for _ in $(seq 200); do
  (( $(wc -l < "$log") >= 4 )) && break
  sleep 0.05
done
kill "$dump"; wait "$dump" 2> /dev/null || true

echo "candump -L vcan0 captured:"
cat "$log"
# Lines look like "(1795258487.377280) vcan0 123#DEADBEEF". The flags nibble of a CAN FD frame
# is printed as the kernel delivers it: 1 (BRS) on older kernels, 5 (BRS|FDF) since Linux 6.x.
expect=('vcan0 123#DEADBEEF'
        'vcan0 1ABCDEF0#R'
        'vcan0 456##[15]AABBCC'
        'vcan0 456##[15]00112233445566778899AABB')
mapfile -t got < "$log"
(( ${#got[@]} == ${#expect[@]} )) || fail "captured ${#got[@]} frames, expected ${#expect[@]}"
for i in "${!expect[@]}"; do
  [[ ${got[$i]} =~ ^\([0-9]+\.[0-9]{6}\)\ ${expect[$i]}$ ]] \
    || fail "frame $i: '${got[$i]}' does not match '${expect[$i]}'"
done
echo "PASS: cansend -> candump -L on vcan0 (classic, extended RTR, CAN FD)"
