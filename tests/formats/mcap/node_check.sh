#!/bin/bash
# One MCAP recording made by hil, checked by the independent reader (node/check_mcap.mjs).
#   node_check.sh MODE HIL NODE CHECK_MJS SOURCE_DIR WORK_DIR
# MODE: export-none|export-zstd|export-lz4 (hil export of the shipped run), export-tf-names (the
# rig's tf: section renames world, the robot base and ee), export-no-tf (hil export --no-tf),
# acquire (hil acquire --play ... --mcap, recorded live), replay (hil replay FILE.mcap seen by hil echo).
set -euo pipefail
mode=$1 hil=$2 node=$3 check=$4 src=$5 work=$6
run=$src/examples/runs/press_slide
rig=$src/examples/rigs/press_bench.yaml
frames=force_plate,object2,object1,robot_base  # the rig's frames, then the robot base
edge=robot_base,ee                             # /tf: the robot base -> ee with every sample
rm -rf "$work" && mkdir -p "$work"
export HIL_DDS_DOMAIN=$((50 + $$ % 10))  # DDS on the host only (default profile), a range no other test uses

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
  *) echo "node_check.sh: unknown mode $mode" >&2; exit 2 ;;
esac
