#!/bin/bash
# Bad MCAP input through the command line: exit status 2 and one line naming the file, the byte
# offset and what is wrong; a killed --mcap acquisition leaves a valid CSV run.   cli_errors.sh HIL SOURCE_DIR WORK_DIR
set -uo pipefail
hil=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
export HIL_DDS_DOMAIN=56  # of the mcap tests' range 50-59, its own (tests/formats/mcap/node_check.sh has 51-55)
fail=0
expect() {  # expect WHAT-IN-STDERR COMMAND...
  local what=$1; shift
  "$@" > "$work/out.txt" 2> "$work/err.txt"
  local rc=$?
  if [[ $rc -ne 2 ]] || ! grep -qF -- "$what" "$work/err.txt"; then
    echo "FAIL: $* -> exit $rc, expected 2 and '$what' in: $(cat "$work/err.txt")" >&2
    fail=1
  fi
}
"$hil" export "$src/examples/runs/press_slide" --mcap "$work/good.mcap" --compression lz4 > /dev/null || exit 1
size=$(stat -c %s "$work/good.mcap")
head -c $((size / 2)) "$work/good.mcap" > "$work/half.mcap"
expect "half.mcap: offset " "$hil" validate "$work/half.mcap"
# replay recovers what it can of a cut file; of this one nothing (its first chunk is cut), and says why.
expect "nothing of it can be replayed: reading stopped at offset" "$hil" replay "$work/half.mcap" --speed 0
expect "runs past the end of the file" "$hil" replay "$work/half.mcap" --speed 0
printf 'not an mcap file at all' > "$work/text.mcap"
expect "text.mcap: offset 0: bad magic" "$hil" replay "$work/text.mcap" --speed 0
head -c $((size - 3)) "$work/good.mcap" > "$work/cut.mcap"
expect "closing magic is missing" "$hil" validate "$work/cut.mcap"
# Options that do not apply are refused by name, nothing written.
expect "--recover copies a recording: it takes no --rig" "$hil" export --recover "$work/good.mcap" --mcap "$work/r.mcap" \
  --rig "$src/examples/rigs/press_bench.yaml"
[[ ! -e $work/r.mcap ]] || { echo "FAIL: export --recover --rig wrote a file" >&2; fail=1; }
expect "--rig is for a run folder" "$hil" replay "$work/good.mcap" --rig "$src/examples/rigs/press_bench.yaml" --speed 0
expect "gzip" "$hil" export "$src/examples/runs/press_slide" --mcap "$work/x.mcap" --compression gzip
# A recording killed mid-way: the CSV run stays valid (the primary record), the MCAP holds its
# complete chunks and is refused as truncated by hil validate, not misread (hil export --recover
# and hil replay save its chunks: node_check.sh killed).
"$hil" acquire --rig "$src/examples/rigs/press_bench.yaml" --out "$work/killed" --play "$src/examples/runs/press_slide" \
  --duration 60 --mcap > /dev/null 2>&1 &
pid=$!
# Killed once the MCAP holds flushed chunks (~1 s of samples; chunks are flushed every second):
# waiting for that, not for a fixed time, keeps the test independent of the machine's load.
for _ in $(seq 300); do
  [[ $(stat -c %s "$work/killed/run.mcap" 2> /dev/null || echo 0) -gt 20000 &&
     $(wc -l < "$work/killed/samples.csv" 2> /dev/null || echo 0) -gt 10 ]] && break
  sleep 0.1
done
sleep 0.3  # and mid-way through the next second's chunk
kill -9 "$pid"
wait "$pid" 2> /dev/null
"$hil" validate "$work/killed" > /dev/null || { echo "FAIL: the CSV run of a killed --mcap acquisition does not validate" >&2; fail=1; }
[[ $(stat -c %s "$work/killed/run.mcap") -gt 20000 ]] || { echo "FAIL: run.mcap of the killed acquisition holds less than ~1 s of chunks after 30 s" >&2; fail=1; }
expect "truncated" "$hil" validate "$work/killed/run.mcap"  # at a chunk boundary or within one
exit $fail
