#!/bin/bash
# Repeats the secure exchange whose teardown Fast DDS 2.9 could abort on (docs/security.md, "Why not
# rtps_protection"): `hil echo -n N` against `hil replay --speed 0`, both --secure, UDP on 127.0.0.1,
# with both cores kept busy. Not part of ctest (minutes, and a rate, not a verdict).
# Usage: stress_teardown.sh HIL SOURCE_DIR [ITERATIONS] [DOMAIN]   (an ASan HIL shows it fastest)
set -u
HIL=$1 SRC=$2 ITER=${3:-100} DOM=${4:-47}
KS=$(mktemp -d /tmp/hil-stress-ks.XXXXXX) LOG=$(mktemp -d /tmp/hil-stress-log.XXXXXX)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$KS"' EXIT
N=$(($(wc -l < "$SRC/examples/runs/press_slide/samples.csv") - 1))
"$HIL" keystore create "$KS" --days 2 > /dev/null &&
  "$HIL" keystore add "$KS" replay --publish /hil/pose_wrench > /dev/null &&
  "$HIL" keystore add "$KS" echo --subscribe rt/hil/pose_wrench > /dev/null || exit 2
PROFILE=(--dds-domain "$DOM" --dds-profile "$SRC/tests/security/dds_udp_loopback.xml" --dds-profile-name hil_udp_loopback)
for _ in 1 2; do sh -c 'while :; do :; done' & done
failed=0
for i in $(seq 1 "$ITER"); do
  "$HIL" "${PROFILE[@]}" --secure "$KS:echo" echo pose_wrench -n "$N" --timeout 20 > "$LOG/echo.out" 2> "$LOG/echo.err" &
  echo_pid=$!
  sleep 0.3
  "$HIL" "${PROFILE[@]}" --secure "$KS:replay" replay "$SRC/examples/runs/press_slide" --speed 0 --wait-subscribers 1 \
    --wait-timeout 15 > /dev/null 2> "$LOG/replay.err"
  replay_rc=$?
  wait $echo_pid
  echo_rc=$?
  if [ $replay_rc != 0 ] || [ $echo_rc != 0 ]; then
    failed=$((failed + 1))
    echo "exchange $i: replay exit $replay_rc, echo exit $echo_rc"
    tail -n 1 "$LOG/replay.err" "$LOG/echo.err"
  fi
done
rm -rf "$LOG"
echo "failed: $failed of $ITER"
[ $failed = 0 ]
