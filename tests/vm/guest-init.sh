#!/bin/sh
# Stage 2 of the hil vcan guest: run by busybox sh from the initramfs' /init, from the per-run
# 9p share /job that run-in-vm.sh filled (this file, config, cmd.sh). Not meant to run on a host.
#
# It mounts the host root read-only at /host, the --rw directories read-write over it, keeps the
# --ro directories that the guest's tmpfs would hide (bound back read-only), makes
# lo, vcan0 and vcan1, runs the command chrooted in /host and writes its exit status to
# /job/status, then powers the guest off.

export PATH=/bin:/sbin
. /job/config

# Milestones with the guest's uptime on the console (run-in-vm.sh -v shows them).
say() { echo "hil-vm guest: $(cut -d" " -f1 /proc/uptime) s: $*" > /dev/console; }
say "stage 2"
finish() {
  echo "$1" > /job/status.tmp && mv /job/status.tmp /job/status
  sync
  poweroff -f
}
fail() { say "$*"; echo "hil-vm guest: $*" >> /job/stderr; finish 125; }

mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=262144,cache=loose hostroot /host \
  || fail "cannot mount the host root (9p tag hostroot)"
# Directories under /tmp, /run, ... that the command needs (run-in-vm.sh --ro, its working
# directory, a script under /tmp): bound aside now, put back once the tmpfs hide the host's.
i=0
while [ "$i" -lt "${HIL_RO_COUNT:-0}" ]; do
  dir=; eval "dir=\$HIL_RO_$i"
  mkdir -p "/keep/$i" && mount -o bind "/host$dir" "/keep/$i" || fail "cannot keep $dir visible"
  i=$((i + 1))
done
mount -t proc proc /host/proc || fail "mount /proc"
mount -t sysfs sysfs /host/sys || fail "mount /sys"
mount -t devtmpfs devtmpfs /host/dev || fail "mount /dev"
mkdir -p /host/dev/pts /host/dev/shm
mount -t devpts -o gid=5,mode=620,ptmxmode=0666 devpts /host/dev/pts
mount -t tmpfs -o mode=1777 tmpfs /host/dev/shm
mount -t tmpfs -o mode=1777 tmpfs /host/tmp || fail "mount /tmp"
mount -t tmpfs -o mode=755 tmpfs /host/run
mount -t tmpfs -o mode=1777 tmpfs /host/var/tmp

i=0
while [ "$i" -lt "${HIL_RO_COUNT:-0}" ]; do
  dir=; eval "dir=\$HIL_RO_$i"
  mkdir -p "/host$dir" 2> /dev/null # on the fresh tmpfs; before the --rw shares, which may lie inside
  mount -o bind "/keep/$i" "/host$dir" || fail "cannot bind $dir back (read-only)"
  i=$((i + 1))
done

i=0
while [ "$i" -lt "$HIL_RW_COUNT" ]; do
  dir=; eval "dir=\$HIL_RW_$i"
  mkdir -p "/host$dir" 2> /dev/null # under /tmp the mount point is on the fresh tmpfs
  mount -t 9p -o "trans=virtio,version=9p2000.L,msize=262144,cache=mmap" "rw$i" "/host$dir" \
    || fail "cannot mount read-write share $dir"
  i=$((i + 1))
done

say "file systems mounted"
hostname hil-vm
# Network devices, with the host's iproute2 in the chroot (busybox ip knows no vcan).
chroot /host /usr/sbin/ip -batch - <<EOT || fail "ip: cannot set up lo, vcan0, vcan1"
link set lo up
link add dev vcan0 type vcan
link set vcan0 mtu 72
link set vcan0 up
link add dev vcan1 type vcan
link set vcan1 mtu 72
link set vcan1 up
EOT

say "lo, vcan0, vcan1 up; running the command"
cp /job/cmd.sh /host/tmp/.hil-vm-cmd.sh

if [ "$HIL_MODE" = shell ]; then
  say "interactive shell in the chroot; 'exit' powers the guest off"
  setsid cttyhack chroot /host /bin/bash /tmp/.hil-vm-cmd.sh
  rc=$?
  say "shell exited with status $rc"
  finish $rc
fi

# </dev/null: the command never reads the console.
chroot /host /bin/bash /tmp/.hil-vm-cmd.sh < /dev/null > /job/stdout 2> /job/stderr
rc=$?
say "command exited with status $rc"
finish $rc
