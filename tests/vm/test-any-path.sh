#!/bin/bash
# vcan harness test (d), run on the host: the harness from a checkout under /tmp, which the guest
# hides behind its own tmpfs. A copy of run-in-vm.sh and guest-init.sh under /tmp/hil-vm-anypath.*
# runs a script living there, from a working directory there, with a build directory there shared
# read-write (--rw inside a kept directory); then a command run from /tmp whose argument is a
# file under /tmp. Checks: exit statuses propagate, the files are visible, the kept directory is
# read-only in the guest and the --rw one writable.
# Usage: test-any-path.sh [path/to/tests/vm]
set -uo pipefail
src=${1:-$(dirname "$(readlink -f "$0")")}
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }
ok() { echo "ok: $*"; }

# /tmp itself, not $TMPDIR: the point is a path the guest hides.
d=$(mktemp -d /tmp/hil-vm-anypath.XXXXXX)
trap 'rm -rf "$d"' EXIT
co=$d/checkout
mkdir -p "$co/tests/vm" "$co/build" "$d/data"
cp "$src/run-in-vm.sh" "$src/guest-init.sh" "$co/tests/vm/"
echo "seen from the guest" > "$co/tests/vm/data.txt"
cat > "$co/tests/vm/probe.sh" <<'PROBE'
#!/bin/bash
here=$(dirname "$0")
echo "probe cwd=$PWD data=$(cat "$here/data.txt") mode=$HIL_VCAN_MODE"
if touch "$here/written" 2> /dev/null; then echo kept-dir=writable; else echo kept-dir=read-only; fi
echo built-in-guest > build/out.txt
exit 37
PROBE
chmod +x "$co/tests/vm/probe.sh"
echo "an argument under /tmp" > "$d/data/in.txt"

# 1. relative command and working directory under /tmp, --rw build dir inside it
(cd "$co" && tests/vm/run-in-vm.sh --timeout 120 --rw "$co/build" -- tests/vm/probe.sh) > "$d/out" 2> "$d/err"
rc=$?
echo "--- stdout"; cat "$d/out"; echo "--- stderr"; cat "$d/err"; echo "---"
mode=$(grep -q 'running on the host' "$d/err" && echo host || echo vm)
((rc == 37)) && ok "exit status 37 of a script under /tmp propagated" || fail "exit status $rc, expected 37"
grep -qxF "probe cwd=$co data=seen from the guest mode=$mode" "$d/out" && ok "script, data and cwd under /tmp visible" \
  || fail "script, data or working directory under /tmp not seen"
[[ $(cat "$co/build/out.txt" 2> /dev/null) == built-in-guest ]] && ok "--rw inside a kept directory written" \
  || fail "the --rw build directory under /tmp was not written"
if [[ $mode == vm ]]; then
  grep -qxF kept-dir=read-only "$d/out" && [[ ! -e $co/tests/vm/written ]] && ok "kept directory read-only in the guest" \
    || fail "the kept directory was writable from the guest"
fi

# 2. absolute harness path, working directory /tmp itself (stays the guest's writable tmpfs),
#    a file argument in another /tmp directory
(cd /tmp && "$co/tests/vm/run-in-vm.sh" --timeout 120 -- \
  /bin/bash -c 'cat "$1"; touch "/tmp/.w$$" || exit 9; exit 3' _ "$d/data/in.txt") > "$d/out" 2> "$d/err"
rc=$?
((rc == 3)) && grep -qxF "an argument under /tmp" "$d/out" && ok "file argument under /tmp visible, /tmp writable, status 3" \
  || { cat "$d/err"; fail "argument under /tmp: status $rc, output $(cat "$d/out")"; }

if ((failures)); then echo "$failures check(s) failed"; exit 1; fi
echo "PASS: run-in-vm.sh from a checkout under /tmp"
