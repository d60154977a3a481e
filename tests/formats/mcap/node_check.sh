#!/bin/bash
# One MCAP recording made by hil, checked by the independent reader (node/check_mcap.mjs).
#   node_check.sh MODE HIL NODE CHECK_MJS SOURCE_DIR WORK_DIR
# MODE: export-none|export-zstd|export-lz4 (hil export of the shipped run), export-tf-names (the
# rig's tf: section renames world, the robot base and ee), export-no-tf (hil export --no-tf),
# acquire (hil acquire --play ... --mcap, recorded live), replay (hil replay FILE.mcap seen by hil echo),
# killed (a live recording ended by kill -9: hil validate refuses it naming what can be saved,
# hil export --recover saves exactly what @mcap/core's streaming reader reads of it, hil replay
# publishes it), import-bag (a ros2 bag of standard topics written by node/make_bag.mjs -> hil import
# -> a run that agrees with its source and that hil diagnose takes).
set -euo pipefail
mode=$1 hil=$2 node=$3 check=$4 src=$5 work=$6
run=$src/examples/runs/press_slide
rig=$src/examples/rigs/press_bench.yaml
frames=force_plate,object2,object1,robot_base  # the rig's frames, then the robot base
edge=robot_base,ee                             # /tf: the robot base -> ee with every sample
rm -rf "$work" && mkdir -p "$work"
# DDS on the host only (default profile), on a domain of the range 50-59 that no other test uses;
# one fixed domain per mode, so that modes ctest runs side by side never hear each other (a pid-drawn
# one let `replay`'s echo count 8 samples of a concurrent `acquire` in CI).
case $mode in
  acquire) export HIL_DDS_DOMAIN=51 ;;
  replay) export HIL_DDS_DOMAIN=52 ;;
  killed) export HIL_DDS_DOMAIN=53 ;;
  import-bag) export HIL_DDS_DOMAIN=54 ;;
  *) export HIL_DDS_DOMAIN=55 ;;
esac

case $mode in
  export-none | export-zstd | export-lz4)
    c=${mode#export-}
    "$hil" export "$run" --rig "$rig" --mcap "$work/press_slide.mcap" --compression "$c"
    "$node" "$check" "$work/press_slide.mcap" "$run/samples.csv" --tf "$frames" --joints 0 --edge "$edge"
    ;;
  export-tf-names)
    # The same rig with ROS names for its frames: one tree map -> base_link -> tool0 on the topics.
    { cat "$rig"; printf 'tf: {world: map, base: base_link, ee: tool0}\n'; } > "$work/rig.yaml"
    "$hil" export "$run" --rig "$work/rig.yaml" --mcap "$work/press_slide.mcap"
    "$node" "$check" "$work/press_slide.mcap" "$run/samples.csv" --tf force_plate,object2,object1,base_link --joints 0 \
      --edge base_link,tool0 --world map
    ;;
  export-no-tf)
    "$hil" export "$run" --rig "$rig" --mcap "$work/press_slide.mcap" --no-tf
    "$node" "$check" "$work/press_slide.mcap" "$run/samples.csv" --tf "$frames" --joints 0
    ;;
  acquire)
    "$hil" acquire --rig "$rig" --out "$work/run" --play "$run" --play-speed 2 --mcap --mcap-compression lz4
    test -s "$work/run/run.mcap"
    # The CSV and the MCAP come from the same samples: every row, value for value.
    "$node" "$check" "$work/run/run.mcap" "$work/run/samples.csv" --tf "$frames" --min-status 2 --edge "$edge"
    ;;
  replay)
    "$hil" export "$run" --mcap "$work/ps.mcap" --compression zstd  # the run's own rig.yaml
    rows=$(($(grep -vc '^#' "$run/samples.csv") - 1))
    "$hil" echo pose_wrench -n "$rows" --timeout 60 > "$work/echo.txt" &
    echo_pid=$!
    "$hil" replay "$work/ps.mcap" --speed 0 --wait-subscribers 1
    wait "$echo_pid"
    got=$(wc -l < "$work/echo.txt")
    if [[ $got -ne $rows ]]; then echo "hil echo saw $got samples of $rows replayed from MCAP" >&2; exit 1; fi
    head -1 "$work/echo.txt" | grep -q '^#0 t=0.0000' || { echo "first echoed sample: $(head -1 "$work/echo.txt")" >&2; exit 1; }
    ;;
  killed)
    "$hil" acquire --rig "$rig" --out "$work/run" --play "$run" --mcap > "$work/acquire.log" 2>&1 &
    pid=$!
    # The recording closes a chunk once a second: wait for two, then kill without warning.
    for _ in $(seq 100); do
      (( $(stat -c %s "$work/run/run.mcap" 2>/dev/null || echo 0) > 20000 )) && break
      sleep 0.1
    done
    sleep 1.2
    kill -9 "$pid"
    wait "$pid" 2>/dev/null || true
    broken=$work/run/run.mcap
    if "$hil" validate "$broken" > "$work/validate.txt" 2>&1; then echo "hil validate accepted a killed recording" >&2; exit 1; fi
    grep -q "without a Footer" "$work/validate.txt" && grep -q "hil export --recover" "$work/validate.txt" ||
      { echo "hil validate of the killed recording: $(cat "$work/validate.txt")" >&2; exit 1; }
    out=$("$hil" export --recover "$broken" --mcap "$work/recovered.mcap")
    echo "$out"
    n=$(sed -nE 's/^recovered ([0-9]+) messages \(([0-9]+) samples\).*/\1/p' <<<"$out")
    s=$(sed -nE 's/^recovered ([0-9]+) messages \(([0-9]+) samples\).*/\2/p' <<<"$out")
    [[ -n $n && $s -gt 0 ]] || { echo "hil export --recover said: $out" >&2; exit 1; }
    # The independent reader streams the same messages out of the killed file, and reads the
    # recovered one to its end.
    peer=$("$node" "$(dirname "$check")/count_messages.mjs" "$broken")
    [[ $peer == "messages $n samples $s incomplete" ]] || { echo "@mcap/core on the killed file: '$peer', hil recovered $n messages, $s samples" >&2; exit 1; }
    peer=$("$node" "$(dirname "$check")/count_messages.mjs" "$work/recovered.mcap")
    [[ $peer == "messages $n samples $s complete" ]] || { echo "@mcap/core on the recovered file: '$peer'" >&2; exit 1; }
    "$hil" validate "$work/recovered.mcap" | grep -q "messages: $n in" || { echo "hil validate of the recovered file" >&2; exit 1; }
    # hil replay reads the killed file itself, says so, and publishes every recovered sample.
    "$hil" echo pose_wrench -n "$s" --timeout 60 > "$work/echo.txt" &
    echo_pid=$!
    "$hil" replay "$broken" --speed 0 --wait-subscribers 1 2> "$work/replay.log"
    wait "$echo_pid"
    grep -q "was not closed or is damaged" "$work/replay.log" || { echo "hil replay did not say the file was cut: $(cat "$work/replay.log")" >&2; exit 1; }
    [[ $(wc -l < "$work/echo.txt") -eq $s ]] || { echo "hil echo saw $(wc -l < "$work/echo.txt") of $s recovered samples" >&2; exit 1; }
    ;;
  import-bag)
    "$node" "$(dirname "$check")/make_bag.mjs" "$run/samples.csv" 1767225600000000000 "$work/bag"
    "$hil" import "$work/bag" --rig "$rig" --out "$work/imported" --wrench /ft/wrench --pose /robot/ee_pose --joints /joint_states
    "$hil" validate "$work/imported" > /dev/null
    /usr/bin/python3 "$(dirname "$0")/compare_import.py" "$run/samples.csv" "$work/imported/samples.csv"
    "$hil" diagnose "$work/imported" > "$work/diagnose.txt" || { cat "$work/diagnose.txt" >&2; exit 1; }
    # The bag's single file as well, and wrong input named.
    "$hil" import "$work/bag/bag_0.mcap" --rig "$rig" --out "$work/from_file" --wrench /ft/wrench --pose /robot/ee_pose > /dev/null
    cmp <(cut -d, -f1-20 "$work/imported/samples.csv") <(cut -d, -f1-20 "$work/from_file/samples.csv") ||
      { echo "the bag folder and its file imported differently" >&2; exit 1; }
    if err=$("$hil" import "$work/bag" --rig "$rig" --out "$work/x" --wrench /nope --pose /robot/ee_pose 2>&1); then exit 1; fi
    grep -q "no topic /nope (the recording has: /ft/wrench, /robot/ee_pose, /joint_states)" <<<"$err" || { echo "$err" >&2; exit 1; }
    if err=$("$hil" import "$work/bag" --rig "$rig" --out "$work/x" --wrench /robot/ee_pose --pose /robot/ee_pose 2>&1); then exit 1; fi
    grep -q "/robot/ee_pose is geometry_msgs/msg/PoseStamped (cdr), expected geometry_msgs/msg/WrenchStamped" <<<"$err" || { echo "$err" >&2; exit 1; }
    # A pose in another frame than the rig's world: hil's own export (world) against a rig naming it map.
    "$hil" export "$run" --rig "$rig" --mcap "$work/hil.mcap" > /dev/null
    { cat "$rig"; printf 'tf: {world: map}\n'; } > "$work/map_rig.yaml"
    if err=$("$hil" import "$work/hil.mcap" --rig "$work/map_rig.yaml" --out "$work/x" 2>&1); then exit 1; fi
    grep -q "hil.mcap: /hil/pose message 0.*frame 'world', expected 'map'" <<<"$err" || { echo "$err" >&2; exit 1; }
    [[ ! -e $work/x ]] || { echo "a refused import left $work/x" >&2; exit 1; }
    # A pose whose quaternion is not unit.
    "$node" "$(dirname "$check")/make_bag.mjs" "$run/samples.csv" 1767225600000000000 "$work/badq" --bad-quaternion > /dev/null
    if err=$("$hil" import "$work/badq" --rig "$rig" --out "$work/x" --wrench /ft/wrench --pose /robot/ee_pose 2>&1); then exit 1; fi
    grep -q "/robot/ee_pose message 100.*unit quaternion (norm 2)" <<<"$err" || { echo "$err" >&2; exit 1; }
    # metadata.yaml naming an absolute path, or a file that is not there.
    sed -i 's|    - bag_0.mcap|    - /etc/hostname|' "$work/badq/metadata.yaml"
    if err=$("$hil" import "$work/badq" --rig "$rig" --out "$work/x" 2>&1); then exit 1; fi
    grep -q "metadata.yaml:.*relative to the bag folder, found '/etc/hostname'" <<<"$err" || { echo "$err" >&2; exit 1; }
    sed -i 's|    - /etc/hostname|    - gone.mcap|' "$work/badq/metadata.yaml"
    if err=$("$hil" import "$work/badq" --rig "$rig" --out "$work/x" 2>&1); then exit 1; fi
    grep -q "metadata.yaml.*no such file: .*gone.mcap" <<<"$err" || { echo "$err" >&2; exit 1; }
    sed -i 's/storage_identifier: mcap/storage_identifier: sqlite3/' "$work/bag/metadata.yaml"
    if err=$("$hil" import "$work/bag" --rig "$rig" --out "$work/x" 2>&1); then exit 1; fi
    grep -q "metadata.yaml:.*storage 'sqlite3': hil reads MCAP storage" <<<"$err" || { echo "$err" >&2; exit 1; }
    ;;
  *) echo "node_check.sh: unknown mode $mode" >&2; exit 2 ;;
esac
