#!/bin/bash
# One fuzz target for a bounded time (what the ctest label `fuzz` runs):
#   run-target.sh BUILD_DIR TARGET SECONDS
# 1. replays every committed crash input in regressions/TARGET (must pass now that it is fixed);
# 2. fuzzes for SECONDS from the seed corpus corpus/TARGET plus the working corpus kept in
#    BUILD_DIR/work/TARGET (it grows from run to run; delete it to start over).
# A finding is saved as BUILD_DIR/artifacts/TARGET-crash-<sha1> and fails the test: fix the
# parser, then commit that file under tests/fuzz/regressions/TARGET/.
set -uo pipefail
here=$(dirname "$(readlink -f "$0")")
bin=${1:?usage: run-target.sh BUILD_DIR TARGET SECONDS}
target=${2:?target}
seconds=${3:?seconds}
exe=$bin/$target
# Leaks inside Debian's libraries (not hil's to fix) are suppressed by name, with the reason there.
export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
[[ -x $exe ]] || { echo "run-target: $exe not built (tests/fuzz/build.sh $bin)" >&2; exit 1; }

regressions=("$here/regressions/$target"/*)
if [[ -e ${regressions[0]} ]]; then
  echo "run-target: $target: replaying ${#regressions[@]} regression input(s)"
  "$exe" -rss_limit_mb=2048 "${regressions[@]}" > "$bin/$target.replay.log" 2>&1
  rc=$?
  grep -vE '^(Running|Executed) ' "$bin/$target.replay.log"
  ((rc == 0)) || { echo "run-target: $target: a regression input fails again (exit $rc)" >&2; exit 1; }
fi

case $target in
  fuzz_rig | fuzz_run_info | fuzz_import_config | fuzz_bag_metadata) dict=(-dict="$here/yaml.dict") ;;
  fuzz_candump) dict=(-dict="$here/candump.dict") ;;
  *) dict=() ;;
esac
mkdir -p "$bin/work/$target" "$bin/artifacts"
"$exe" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len=8192 -print_final_stats=1 \
  "${dict[@]}" -artifact_prefix="$bin/artifacts/$target-" "$bin/work/$target" "$here/corpus/$target" \
  > "$bin/work/$target.log" 2>&1
rc=$?
grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$bin/work/$target.log"
if ((rc != 0)); then
  tail -n 60 "$bin/work/$target.log" >&2
  echo "run-target: $target: FINDING (exit $rc); input saved as $(ls -t "$bin/artifacts/$target-"* 2> /dev/null | head -1)" >&2
  exit 1
fi
echo "run-target: $target: no finding in $seconds s"
