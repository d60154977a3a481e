#!/bin/bash
# vcan harness test (c), run on the host: run-in-vm.sh itself.
#   - a failing command's exit status (42) is run-in-vm.sh's; stdout and stderr come back apart;
#     arguments (spaces, quotes, $) arrive intact; the caller's environment and working directory
#     are the command's; a --rw directory is written from inside and seen on the host;
#   - --timeout kills the run and fails with 124;
#   - with no prepared kernel (HIL_VM_DIR empty) a forced VM run fails with 125 and names
#     prepare.sh (on a host without SocketCAN this is what every vcan test does then).
# Usage: test-harness.sh [path/to/run-in-vm.sh]
set -uo pipefail
RUN=${1:-$(dirname "$(readlink -f "$0")")/run-in-vm.sh}
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }
ok() { echo "ok: $*"; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/hil-vm-harness.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/rw"

# 1. exit status, output, arguments, environment, cwd, --rw (one boot)
start=$SECONDS
(cd "$tmp/rw" && HIL_HARNESS_PROBE='v a l' "$RUN" --timeout 120 --rw "$tmp/rw" -- \
  bash -c 'printf "<%s>" "$@"; echo; echo "cwd=$PWD probe=$HIL_HARNESS_PROBE mode=$HIL_VCAN_MODE"
           echo to-stderr >&2; echo written-in-guest > rw-check; exit 42' \
  _ 'a b' "c'd" '$HOME') > "$tmp/out" 2> "$tmp/err"
rc=$?
echo "--- stdout"; cat "$tmp/out"; echo "--- stderr"; cat "$tmp/err"; echo "---"
((rc == 42)) && ok "exit status 42 propagated" || fail "exit status $rc, expected 42"
grep -qxF "<a b><c'd><\$HOME>" "$tmp/out" && ok "arguments intact" || fail "arguments mangled"
grep -qxF "cwd=$tmp/rw probe=v a l mode=$(grep -q 'running on the host' "$tmp/err" && echo host || echo vm)" \
  "$tmp/out" && ok "cwd and environment" || fail "cwd or environment not passed"
grep -qxF to-stderr "$tmp/err" && ! grep -q to-stderr "$tmp/out" && ok "stderr apart from stdout" \
  || fail "stderr not passed apart"
[[ $(cat "$tmp/rw/rw-check" 2> /dev/null) == written-in-guest ]] && ok "--rw directory written" \
  || fail "file written in the --rw directory not seen on the host"
echo "(run 1 took $((SECONDS - start)) s)"

# 2. hard timeout
start=$SECONDS
"$RUN" --timeout 3 -- sleep 600 > "$tmp/out" 2> "$tmp/err"
rc=$?
took=$((SECONDS - start))
((rc == 124)) && ok "timeout gives 124" || { cat "$tmp/err"; fail "timeout gave $rc, expected 124"; }
((took < 20)) && ok "timeout honoured ($took s for --timeout 3)" || fail "timeout took $took s"

# 3. no prepared kernel: fail (not pass) and tell what to run
HIL_VM_DIR=$tmp/no-such-cache "$RUN" --vm -- true > "$tmp/out" 2> "$tmp/err"
rc=$?
((rc == 125)) && grep -q 'prepare.sh' "$tmp/err" && ok "missing kernel: 125 and names prepare.sh" \
  || { cat "$tmp/err"; fail "missing kernel gave $rc"; }

if ((failures)); then echo "$failures check(s) failed"; exit 1; fi
echo "PASS: run-in-vm.sh harness"
