#!/bin/bash
# A second DDS vendor beside hil (docs/ros.md, "Eclipse Cyclone DDS"): cyclone_peer (Debian's
# Cyclone DDS, configured by idl/profiles/cyclonedds_localhost.xml) runs while `hil acquire` plays
# the shipped run on the fake rig, then publishes into hil while `hil echo tf` listens.
#   cyclone_check.sh HIL PEER SOURCE_DIR WORK_DIR
# Checks: 1. discovery shows every hil writer with ROS 2's type name and the QoS docs/ros.md's table
# states (written out below, not taken from hil's code); 2. each standard topic arrives, decoded
# by the other vendor's code from its own type definitions (tests/interop/ros2_types.idl), and a
# wrench is value for value a reading of the run's raw/force_plate.csv and a PoseWrenchSample the
# run's sample of its index (hil_msgs as ros/hil_msgs defines them); 3. hil receives the peer's
# tf2_msgs/TFMessage.
set -euo pipefail
hil=$1 peer=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
export HIL_DDS_DOMAIN=$((80 + $$ % 10))  # 80-89: no other test uses them
export CYCLONEDDS_URI=file://$src/idl/profiles/cyclonedds_localhost.xml
fail() { echo "FAIL: $*" >&2; echo "--- peer:" >&2; cat "$work/peer.txt" "$work/peer.err" >&2 || true; exit 1; }

"$peer" "$HIL_DDS_DOMAIN" 3 > "$work/peer.txt" 2> "$work/peer.err" &
pid=$!
sleep 1
"$hil" acquire --rig "$src/examples/rigs/press_bench.yaml" --out "$work/run" --play "$src/examples/runs/press_slide" \
  --play-speed 2 > "$work/acquire.log" 2>&1 || { cat "$work/acquire.log" >&2; fail "hil acquire"; }
"$hil" echo tf -n 3 --timeout 60 > "$work/echo.txt" || fail "hil echo tf received $(grep -c transforms "$work/echo.txt") of the peer's 3 messages"
wait "$pid" || fail "cyclone_peer did not get every topic or could not send"
out=$(cat "$work/peer.txt")

# 1. The writers as the other vendor's discovery sees them (docs/ros.md, "Topics").
for want in \
  "rt/hil/wrench geometry_msgs::msg::dds_::WrenchStamped_ reliable volatile" \
  "rt/hil/pose geometry_msgs::msg::dds_::PoseStamped_ reliable volatile" \
  "rt/hil/joint_states sensor_msgs::msg::dds_::JointState_ reliable volatile" \
  "rt/tf_static tf2_msgs::msg::dds_::TFMessage_ reliable transient_local" \
  "rt/tf tf2_msgs::msg::dds_::TFMessage_ reliable volatile" \
  "rt/diagnostics diagnostic_msgs::msg::dds_::DiagnosticArray_ reliable volatile" \
  "rt/hil/pose_wrench hil_msgs::msg::dds_::PoseWrenchSample_ reliable volatile" \
  "rt/hil/device_status hil_msgs::msg::dds_::DeviceStatus_ reliable transient_local"; do
  grep -qxF "writer $want" <<<"$out" || fail "no writer '$want'"
done
[[ $(grep -c '^writer ' <<<"$out") -eq 8 ]] || fail "expected the acquirer's 8 writers, discovery shows $(grep -c '^writer ' <<<"$out")"

# 2. Every topic arrived, decoded by Cyclone's code.
grep -qE '^got rt/hil/wrench [1-9][0-9]* frame force_plate stamp ' <<<"$out" || fail "wrench"
grep -qE '^got rt/hil/pose [1-9][0-9]* frame world stamp [0-9]+\.[0-9]{9} qw 1$' <<<"$out" || fail "pose"
grep -qE '^got rt/tf [1-9][0-9]* transforms 1 first robot_base -> ee$' <<<"$out" || fail "tf"
grep -qE '^got rt/tf_static 1 transforms 4 first world -> force_plate$' <<<"$out" || fail "tf_static (latched: the peer joined before)"
grep -qE '^got rt/diagnostics [1-9][0-9]* status [12] first hil/(force_plate|robot)$' <<<"$out" || fail "diagnostics"
grep -qE '^got rt/hil/joint_states [1-9][0-9]* names 6 first j1 positions 6$' <<<"$out" || fail "joint_states (the rig's joints, unnamed: j1..j6)"
grep -qE '^got rt/hil/device_status [1-9][0-9]* device (force_plate|robot) state [0-3]$' <<<"$out" || fail "device_status"
# A received PoseWrenchSample is the run's sample of its index, value for value (samples.csv).
read -r index sfz < <(sed -nE 's/^got rt\/hil\/pose_wrench [0-9]+ index ([0-9]+) fz ([^ ]+) pz .*$/\1 \2/p' <<<"$out")
[[ -n $index ]] || fail "pose_wrench"
csv_fz=$(awk -F, -v i="$index" '/^#/ { next } !h { for (c = 1; c <= NF; ++c) if ($c == "fz") col = c; h = 1; next } n++ == i { print $col; exit }' \
  "$work/run/samples.csv")
awk -v a="$csv_fz" -v b="$sfz" 'BEGIN { exit !(a != "" && a + 0 == b + 0) }' || fail "pose_wrench sample $index: fz $sfz, samples.csv has '$csv_fz'"
# A received wrench is a reading of the run: its stamp is a raw row's t_ns and its fz that row's fz.
read -r sec nsec fz < <(sed -nE 's/^got rt\/hil\/wrench [0-9]+ frame force_plate stamp ([0-9]+)\.([0-9]{9}) fz (.*)$/\1 \2 \3/p' <<<"$out")
t_ns="$sec$nsec"
row=$(awk -F, -v t="$t_ns" 'NR > 1 && $1 == t { print $13 }' "$work/run/raw/force_plate.csv")
[[ -n $row ]] || fail "no raw reading at the received wrench's stamp $t_ns"
awk -v a="$row" -v b="$fz" 'BEGIN { exit !(a + 0 == b + 0) }' || fail "received fz $fz, raw/force_plate.csv has $row at $t_ns"

# 3. hil received what the other vendor published.
grep -q '^sent 3$' <<<"$out" || fail "the peer sent $(sed -n 's/^sent //p' <<<"$out") of 3"
[[ $(grep -c 'world -> cyclone_frame p=\[0 0 0\]\|world -> cyclone_frame p=\[0.25 0 0\]\|world -> cyclone_frame p=\[0.5 0 0\]' "$work/echo.txt") -eq 3 ]] ||
  fail "hil echo tf: $(cat "$work/echo.txt")"
echo "interop.cyclone: all checks passed"
