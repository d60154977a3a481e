#!/bin/bash
# The fuzz targets for longer than the default suite's 10 s, one after the other:
#   tests/fuzz/run-long.sh SECONDS [TARGET...]      (default: every target)
# Builds them first (tests/fuzz/build.sh, in $HIL_FUZZ_BUILD or build/fuzz), replays the
# committed regressions, fuzzes each for SECONDS and prints one line per target: executions,
# executions/s, coverage (cov = edges, ft = features), corpus size and the finding if any.
# Exit status 1 when a target found something (input under <build>/fuzz/artifacts/).
set -uo pipefail
here=$(dirname "$(readlink -f "$0")")
root=$(cd "$here/../.." && pwd)
seconds=${1:?usage: run-long.sh SECONDS [TARGET...]}
shift
bin=${HIL_FUZZ_BUILD:-$root/build/fuzz}
targets=("$@")
# Default: every target that has a seed corpus (the list cannot fall behind the targets).
if ((${#targets[@]} == 0)); then
  for d in "$here"/corpus/*/; do targets+=("$(basename "$d")"); done
fi
mkdir -p "$bin"
"$here/build.sh" "$bin" || exit 1
found=0
printf '%-22s %12s %9s %7s %7s %12s  %s\n' target executions exec/s cov ft corpus finding
for t in "${targets[@]}"; do
  "$here/run-target.sh" "$bin" "$t" "$seconds" > "$bin/work/$t.long" 2>&1
  rc=$?
  log=$bin/work/$t.log
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -1)
  [[ -n $done_line ]] || done_line=$(grep -E '^#[0-9]+[[:space:]]' "$log" | tail -1)
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  cov=$(grep -oE 'cov: [0-9]+' <<< "$done_line" | cut -d' ' -f2)
  ft=$(grep -oE 'ft: [0-9]+' <<< "$done_line" | cut -d' ' -f2)
  corp=$(grep -oE 'corp: [0-9]+/[0-9]+[a-zA-Z]*' <<< "$done_line" | cut -d' ' -f2)
  finding=none
  if ((rc != 0)); then
    found=1
    finding=$(grep -m1 -oE 'ERROR: [A-Za-z]+: .*|unexpected exception .*|property violated: .*|regression input fails again' "$bin/work/$t.long" "$log" | head -1 | cut -d: -f2-)
  fi
  printf '%-22s %12s %9s %7s %7s %12s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$finding"
done
exit $found
