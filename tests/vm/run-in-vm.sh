#!/bin/bash
# Run a command where real SocketCAN with vcan0 and vcan1 is available (see tests/vm/README.md).
#
#   run-in-vm.sh [OPTIONS] -- COMMAND ARGS...
#
# On a host whose kernel has SocketCAN (vcan0 exists or can be created) the command runs
# directly on the host. Otherwise it boots Debian's kernel under QEMU (TCG), with the host root
# shared read-only over 9p and chrooted, and runs the command there on vcan0/vcan1.
# The command's stdout and stderr are printed, and its exit status is this script's.
#
# Options:
#   --timeout SECONDS  hard limit for the whole run, boot included (default 300); on expiry
#                      QEMU (or the host command) is killed and the exit status is 124
#   --rw DIR           share DIR read-write at the same path in the guest (repeatable)
#   --ro DIR           keep DIR visible (read-only) although it lies under /tmp, /var/tmp or
#                      /run, which the guest replaces by fresh tmpfs (repeatable). Done by itself
#                      for the working directory and for COMMAND and arguments naming such paths.
#   --shell            interactive: a bash in the guest on this terminal (COMMAND optional)
#   --vm | --host      force the VM, or force running on the host (default: auto)
#   --smp N            guest CPUs (default 1, or HIL_VM_SMP)
#   -v, --verbose      print the guest's kernel console at the end
#   -h, --help
#
# Environment: HIL_VM_DIR (cache from prepare.sh, default /var/cache/hil-vm), HIL_VM_MODE
# (auto|vm|host), HIL_VM_SMP, HIL_VM_KEEP=1 (keep the per-run job directory for debugging);
# for experiments: HIL_VM_KERNEL (e.g. $HIL_VM_DIR/vmlinuz), HIL_VM_CPU (default max),
# HIL_VM_APPEND (more kernel parameters), HIL_VM_QEMU_ARGS (more QEMU arguments).
# The command sees HIL_VCAN_MODE=vm or host.
# Exit status: COMMAND's; 124 timeout; 125 harness failure (no kernel, guest crashed, ...).
set -uo pipefail

SELF_DIR=$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")
VM_DIR=${HIL_VM_DIR:-/var/cache/hil-vm}
TIMEOUT=300
MODE=${HIL_VM_MODE:-auto}
SMP=${HIL_VM_SMP:-1}
SHELL_MODE=0
VERBOSE=0
RW=()
RO=()

msg() { printf 'run-in-vm: %s\n' "$*" >&2; }
die() { msg "error: $*"; exit 125; }
usage() { sed -n '2,/^set -uo/{/^set -uo/d;s/^# \{0,1\}//;p}' "${BASH_SOURCE[0]}"; }

while (($#)); do
  case $1 in
    --timeout) TIMEOUT=${2:?--timeout needs a value}; shift 2 ;;
    --timeout=*) TIMEOUT=${1#*=}; shift ;;
    --rw) RW+=("${2:?--rw needs a directory}"); shift 2 ;;
    --rw=*) RW+=("${1#*=}"); shift ;;
    --ro) RO+=("${2:?--ro needs a directory}"); shift 2 ;;
    --ro=*) RO+=("${1#*=}"); shift ;;
    --shell) SHELL_MODE=1; shift ;;
    --vm) MODE=vm; shift ;;
    --host) MODE=host; shift ;;
    --smp) SMP=${2:?--smp needs a value}; shift 2 ;;
    -v|--verbose) VERBOSE=1; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; break ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) break ;;
  esac
done
(($# > 0 || SHELL_MODE)) || { usage >&2; exit 125; }
[[ $TIMEOUT =~ ^[0-9]+$ && $TIMEOUT -gt 0 ]] || die "--timeout wants a positive number of seconds"
[[ $SMP =~ ^[0-9]+$ && $SMP -gt 0 ]] || die "--smp wants a positive number"
case $MODE in auto|vm|host) ;; *) die "HIL_VM_MODE must be auto, vm or host" ;; esac
for i in "${!RW[@]}"; do
  [[ -d ${RW[$i]} ]] || die "--rw ${RW[$i]}: not a directory"
  RW[$i]=$(readlink -f "${RW[$i]}")
done
for i in "${!RO[@]}"; do
  [[ -d ${RO[$i]} ]] || die "--ro ${RO[$i]}: not a directory"
  RO[$i]=$(readlink -f "${RO[$i]}")
done
CWD=$(pwd -P)

# --- on the host, if its kernel has SocketCAN ---------------------------------------------------
ip_cmd=$(command -v ip || echo /usr/sbin/ip)
is_vcan() { "$ip_cmd" -details link show dev "$1" 2> /dev/null | grep -qw vcan; }
host_vcan() {   # make vcan0 (required) and vcan1 (wanted) usable on the host
  local dev
  [[ -x $ip_cmd ]] || return 1
  for dev in vcan0 vcan1; do
    if ! is_vcan "$dev"; then
      [[ $(id -u) == 0 ]] || { [[ $dev == vcan0 ]] && return 1 || continue; }
      modprobe -q vcan 2> /dev/null
      "$ip_cmd" link add dev "$dev" type vcan 2> /dev/null || { [[ $dev == vcan0 ]] && return 1 || continue; }
      "$ip_cmd" link set "$dev" mtu 72 2> /dev/null
    fi
    if ! "$ip_cmd" link show dev "$dev" | grep -q '[<,]UP[,>]'; then
      "$ip_cmd" link set "$dev" up 2> /dev/null || { [[ $dev == vcan0 ]] && return 1; }
    fi
  done
  return 0
}

if [[ $MODE == host ]] || { [[ $MODE == auto && $SHELL_MODE == 0 ]] && host_vcan; }; then
  if [[ $MODE == host ]]; then
    host_vcan || msg "warning: vcan0 is not usable on this host"
    msg "running on the host, without the VM (--host)"
  else
    msg "the host kernel has SocketCAN: running on the host, without the VM (vcan0$(is_vcan vcan1 && echo ', vcan1'))"
  fi
  export HIL_VCAN_MODE=host
  if ((SHELL_MODE)); then exec "${SHELL:-/bin/bash}" -l; fi
  # --foreground only on a terminal (so Ctrl-C and job control work); otherwise timeout
  # runs the command in its own process group and kills its children too.
  fg=(); [[ -t 0 ]] && fg=(--foreground)
  timeout "${fg[@]}" --kill-after=10 "$TIMEOUT" "$@"
  rc=$?
  ((rc == 124)) && msg "error: timeout after $TIMEOUT s: $*"
  exit $rc
fi

# --- in the guest ------------------------------------------------------------------------------
[[ -f $VM_DIR/vmlinux && -f $VM_DIR/initramfs.cpio.gz && -f $VM_DIR/stamp ]] || die \
  "no guest kernel in $VM_DIR and the host kernel has no SocketCAN (no vcan0).
  Run once, as root:  $SELF_DIR/prepare.sh
  (HIL_VM_DIR selects another cache directory.)"
command -v qemu-system-x86_64 > /dev/null || die "qemu-system-x86_64 missing: run $SELF_DIR/prepare.sh"
if ((SHELL_MODE)) && ! [[ -t 0 && -t 1 ]]; then die "--shell needs a terminal"; fi

job=$(mktemp -d "${TMPDIR:-/tmp}/hil-vm.XXXXXX") || die "mktemp failed"
qpid=
cleanup() {
  [[ -n $qpid ]] && kill "$qpid" 2> /dev/null
  if [[ ${HIL_VM_KEEP:-0} == 1 ]]; then msg "job directory kept: $job"; else rm -rf "$job"; fi
}
trap cleanup EXIT
trap 'msg "interrupted"; exit 130' INT
trap 'msg "terminated"; exit 143' TERM HUP

sq() { printf "'%s'" "${1//\'/\'\\\'\'}"; }   # single-quote for busybox sh

# The guest mounts fresh tmpfs on these (guest-init.sh); what the command needs from under them
# is bound back read-only from the host root before (a checkout or build under /tmp works so).
under() { local d=$1; shift; local p; for p; do [[ $d == "$p" || $d == "$p"/* ]] && return 0; done; return 1; }
HIDDEN=(/tmp /var/tmp /run /dev/shm)
keep_visible() {   # keep_visible PATH: its directory (itself if a directory) becomes an --ro dir
  local p
  p=$(readlink -f -- "$1" 2> /dev/null) || return 0
  [[ -e $p ]] || return 0
  [[ -d $p ]] || p=$(dirname -- "$p")
  # Strictly below: /tmp itself stays the guest's writable tmpfs (an empty one is fine as cwd).
  [[ " ${HIDDEN[*]} " == *" $p "* ]] && return 0
  under "$p" "${HIDDEN[@]}" && ! under "$p" "${RW[@]}" && RO+=("$p")
  return 0
}
if ((SHELL_MODE == 0)); then
  keep_visible "$CWD"
  if [[ $1 == */* ]]; then keep_visible "$1"; else keep_visible "$(command -v -- "$1" || true)"; fi
  for a in "${@:2}"; do [[ $a == /* || $a == ./* || $a == ../* ]] && keep_visible "$a"; done
else
  keep_visible "$CWD"
fi
# Outermost first, each once (a directory inside another one is visible with it).
ro_kept=()
while IFS= read -r d; do
  [[ " ${HIDDEN[*]} " == *" $d "* ]] && die "--ro $d: the guest needs its own writable $d; name a directory below it"
  [[ -n $d ]] && ! under "$d" "${ro_kept[@]}" && ro_kept+=("$d")
done < <(printf '%s\n' "${RO[@]}" | sort -u)
RO=("${ro_kept[@]}")
((${#RO[@]} && VERBOSE)) && msg "kept visible (read-only) in the guest: ${RO[*]}"

# config for guest-init.sh (busybox sh)
{
  echo "HIL_MODE=$( ((SHELL_MODE)) && echo shell || echo run)"
  echo "HIL_RW_COUNT=${#RW[@]}"
  for i in "${!RW[@]}"; do echo "HIL_RW_$i=$(sq "${RW[$i]}")"; done
  echo "HIL_RO_COUNT=${#RO[@]}"
  for i in "${!RO[@]}"; do echo "HIL_RO_$i=$(sq "${RO[$i]}")"; done
} > "$job/config"
cp "$SELF_DIR/guest-init.sh" "$job/guest-init.sh"

# cmd.sh, run by the host's bash in the chroot: the caller's environment (less what makes no
# sense in the guest), its working directory, then COMMAND.
under_rw() { local d; for d in "${RW[@]}"; do [[ $1 == "$d" || $1 == "$d"/* ]] && return 0; done; return 1; }
{
  echo 'rm -f -- "$0"'
  echo 'for v in $(compgen -e); do unset "$v"; done'
  while IFS= read -r -d '' kv; do
    name=${kv%%=*}
    [[ $name =~ ^[A-Za-z_][A-Za-z0-9_]*$ ]] || continue
    case $name in
      BASH_*|SHLVL|PWD|OLDPWD|_|DISPLAY|WAYLAND_DISPLAY|XAUTHORITY|XDG_RUNTIME_DIR|SSH_*|\
      DBUS_SESSION_BUS_ADDRESS|TMPDIR|TMP|TEMP|HIL_VCAN_MODE|TERM) continue ;;
    esac
    printf 'export %s=%q\n' "$name" "${kv#*=}"
  done < <(env -0)
  [[ :${PATH:-}: == *:/usr/sbin:* ]] || echo 'export PATH="${PATH:+$PATH:}/usr/sbin:/sbin"'
  [[ -n ${PATH:-} ]] || echo 'export PATH=/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin'
  if [[ -n ${TMPDIR:-} ]] && under_rw "$TMPDIR"; then printf 'export TMPDIR=%q\n' "$TMPDIR"
  else echo 'export TMPDIR=/tmp'; fi
  if ((SHELL_MODE)); then echo "export TERM=$(printf %q "${TERM:-vt100}")"; else echo 'export TERM=dumb'; fi
  echo 'export HIL_VCAN_MODE=vm'
  printf 'cd -- %q || { echo "run-in-vm: cannot enter %q in the guest (pass it with --rw or --ro)" >&2; exit 126; }\n' "$CWD" "$CWD"
  if (($# == 0)); then echo 'exec /bin/bash -l'
  else printf 'exec'; printf ' %q' "$@"; printf '\n'; fi
} > "$job/cmd.sh"
: > "$job/stdout"; : > "$job/stderr"

qemu=(qemu-system-x86_64 -accel tcg -cpu "${HIL_VM_CPU:-max}" -smp "$SMP" -m 1024 -nographic -no-reboot
      -nodefaults -nic none
      -kernel "${HIL_VM_KERNEL:-$VM_DIR/vmlinux}" -initrd "$VM_DIR/initramfs.cpio.gz"
      -append "console=ttyS0 panic=-1 quiet loglevel=4 i8042.noaux i8042.nokbd i8042.nopnp mitigations=off tsc=reliable no_timer_check cryptomgr.notests init_on_alloc=0 audit=0 nmi_watchdog=0 rcupdate.rcu_expedited=1 ${HIL_VM_APPEND:-}"
      -virtfs "local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap"
      -virtfs "local,path=${job//,/,,},mount_tag=hiljob,security_model=none")
# shellcheck disable=SC2206 # debugging knobs, split on purpose
qemu+=(${HIL_VM_QEMU_ARGS:-})
for i in "${!RW[@]}"; do
  qemu+=(-virtfs "local,path=${RW[$i]//,/,,},mount_tag=rw$i,security_model=none,multidevs=remap")
done

if ((SHELL_MODE)); then
  msg "booting the guest (interactive; Ctrl-A x kills QEMU)"
  "${qemu[@]}" -serial mon:stdio
  rc=$(cat "$job/status" 2> /dev/null || echo 125)
  exit "$rc"
fi

qemu+=(-serial "file:$job/console.log" -monitor none)
t0=$EPOCHREALTIME
timeout --kill-after=5 "$TIMEOUT" "${qemu[@]}" < /dev/null > "$job/qemu.log" 2>&1 &
qpid=$!
tail -n +1 -F -s 0.2 --pid="$qpid" "$job/stdout" 2> /dev/null &
t1=$!
tail -n +1 -F -s 0.2 --pid="$qpid" "$job/stderr" >&2 2> /dev/null &
t2=$!
wait "$qpid"
qrc=$?
qpid=
wait "$t1" "$t2"
t1_=$EPOCHREALTIME
us=$(( (${t1_%.*} - ${t0%.*}) * 1000000 + 10#${t1_#*.} - 10#${t0#*.} ))
secs=$(printf '%d.%d' $((us / 1000000)) $((us % 1000000 / 100000)))

show_console() { msg "guest console:"; sed 's/\r$//; s/^/  | /' "$job/console.log" "$job/qemu.log" >&2; }
if [[ -s $job/status ]]; then
  rc=$(cat "$job/status")
  ((VERBOSE)) && show_console
  ((rc == 125)) && show_console
  msg "guest run: exit status $rc, $secs s (boot + command + poweroff)"
  exit "$rc"
fi
show_console
if ((qrc == 124 || qrc == 137)); then
  msg "error: timeout after $TIMEOUT s; QEMU killed: $*"
  exit 124
fi
msg "error: the guest stopped without an exit status (QEMU exit $qrc): $*"
exit 125
