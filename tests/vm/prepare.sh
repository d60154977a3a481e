#!/bin/bash
# Prepare the QEMU guest used by the vcan tests (see tests/vm/README.md).
#
# Run as root on a Debian 12 machine, after `apt-get update` (it runs it itself if apt cannot
# find a package). Idempotent: a second run with an up-to-date cache checks the packages and the
# stamp and exits in well under a second (about 15-30 s when it has to build the cache).
#
#   HIL_VM_DIR   cache directory (default /var/cache/hil-vm)
#   HIL_VM_FORCE=1  rebuild even if the cache is up to date
#
# What it does:
#   1. apt-get install the host tools (qemu-system-x86, busybox-static, cpio, kmod, can-utils,
#      python3-can, iproute2, xz-utils), only when one is missing;
#   2. apt-get download the kernel package that linux-image-amd64 depends on (Debian's own
#      kernel, which has CAN, vcan and 9p as modules);
#   3. extract vmlinuz and the needed modules (dependencies resolved with modinfo); unpack the
#      kernel to an ELF vmlinux, which QEMU boots directly (PVH entry): no xz decompression
#      under TCG, about 3 s less per boot; strip the modules' signatures (verifying them costs
#      TCG time too; the guest kernel is only tainted);
#   4. pack a busybox initramfs whose /init loads the modules, mounts the per-run 9p share
#      "hiljob" and hands over to the guest-init.sh that run-in-vm.sh put there.
set -euo pipefail

DIR=${HIL_VM_DIR:-/var/cache/hil-vm}
SELF=$(readlink -f "${BASH_SOURCE[0]}")
log() { printf 'prepare.sh: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

# Modules wanted in the guest; their dependencies are added by modinfo.
ROOT_MODULES=(can can-raw can-bcm can-isotp can-dev vcan vxcan virtio_pci 9pnet_virtio 9p)
HOST_PACKAGES=(qemu-system-x86 busybox-static cpio kmod can-utils python3-can iproute2 xz-utils)

[[ $(id -u) == 0 ]] || die "run as root (it installs packages with apt-get)"

# --- 1. host packages --------------------------------------------------------------------------
missing=()
declare -A status=()
while read -r p st; do status[$p]=$st; done \
  < <(dpkg-query -W -f='${Package} ${db:Status-Status}\n' "${HOST_PACKAGES[@]}" 2> /dev/null || true)
for p in "${HOST_PACKAGES[@]}"; do
  [[ ${status[$p]:-} == installed ]] || missing+=("$p")
done
updated=0
apt_update() { ((updated)) || { log "apt-get update"; apt-get update -qq >&2; updated=1; }; }
if ((${#missing[@]})); then
  log "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q --no-install-recommends "${missing[@]}" >&2 \
    || { apt_update && apt-get install -y -q --no-install-recommends "${missing[@]}" >&2; } \
    || die "apt-get install ${missing[*]} failed"
fi

# --- 2. which kernel ---------------------------------------------------------------------------
mkdir -p "$DIR"
exec 9>"$DIR/.lock"
flock 9

selfsum=$(sha256sum "$SELF" | cut -d' ' -f1)
cached_ok() { [[ -f $DIR/stamp && -f $DIR/vmlinux && -f $DIR/initramfs.cpio.gz ]]; }
# Fast path without apt-cache (which takes 1-2 s here): same script, and apt's package lists
# not updated since the cache was made.
if [[ ${HIL_VM_FORCE:-0} != 1 ]] && cached_ok && [[ $(cut -d' ' -f3 "$DIR/stamp") == "$selfsum" ]] \
   && [[ -z $(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages*' -newer "$DIR/stamp" 2> /dev/null) ]]; then
  log "up to date in $DIR ($(cut -d' ' -f1,2 "$DIR/stamp"))"
  exit 0
fi

# One apt-cache call (it is most of a no-op run's second): linux-image-amd64's version and the
# versioned kernel package it depends on, e.g. "Depends: linux-image-6.1.0-56-amd64 (= 6.1.192-2)".
meta=$(apt-cache show --no-all-versions linux-image-amd64 2> /dev/null || true)
if [[ -z $meta ]] && ! cached_ok; then   # a machine where apt-get update never ran
  apt_update || true
  meta=$(apt-cache show --no-all-versions linux-image-amd64 2> /dev/null || true)
fi
kpkg=$(sed -n 's/^Depends: .*\(linux-image-[0-9][^ ,]*\).*/\1/p' <<< "$meta" | head -n1)
kver_deb=$(sed -n 's/^Depends: .*linux-image-[0-9][^ ,]* (= \([^)]*\)).*/\1/p' <<< "$meta" | head -n1)
[[ -n $kver_deb ]] || kver_deb=$(sed -n 's/^Version: //p' <<< "$meta" | head -n1)
if [[ -z $kpkg || -z $kver_deb ]]; then
  if [[ -f $DIR/stamp ]]; then
    log "apt-cache knows no linux-image-amd64 (no apt-get update?); keeping the cached kernel"
    exit 0
  fi
  die "apt-cache cannot resolve linux-image-amd64: run apt-get update first"
fi
want="$kpkg $kver_deb $selfsum"

if [[ ${HIL_VM_FORCE:-0} != 1 && $(cat "$DIR/stamp" 2> /dev/null) == "$want" ]] && cached_ok; then
  touch "$DIR/stamp"
  log "up to date in $DIR ($kpkg $kver_deb)"
  exit 0
fi

# --- 3. download and extract -------------------------------------------------------------------
work=$(mktemp -d "$DIR/.build.XXXXXX")
trap 'rm -rf "$work"' EXIT
log "downloading $kpkg ($kver_deb)"
# (the "download is performed unsandboxed" notice is apt's: the directory is root's own)
(cd "$work" && apt-get download -q "$kpkg=$kver_deb" 2>&1 | grep -v 'unsandboxed' >&2) || true
ls "$work"/*.deb > /dev/null 2>&1 || die "apt-get download $kpkg=$kver_deb failed"
deb=$(ls "$work"/*.deb)
log "extracting $(basename "$deb")"
mkdir "$work/pkg"
dpkg-deb --fsys-tarfile "$deb" \
  | tar -x -C "$work/pkg" --wildcards './boot/vmlinuz-*' './lib/modules/*/kernel/*' \
        './lib/modules/*/modules.builtin'
kdir=$(echo "$work"/pkg/lib/modules/*)
kver=$(basename "$kdir")
[[ -f $work/pkg/boot/vmlinuz-$kver ]] || die "no vmlinuz-$kver in $deb"

# name -> path of every module in the package (module names treat - and _ alike)
declare -A modpath=()
while IFS= read -r f; do
  n=${f##*/}; n=${n%.ko}; modpath[${n//-/_}]=$f
done < <(find "$kdir/kernel" -name '*.ko')
declare -A builtin=()
while IFS= read -r f; do
  n=${f##*/}; n=${n%.ko}; builtin[${n//-/_}]=1
done < "$kdir/modules.builtin"

# Depth-first: dependencies before the module itself.
declare -A seen=()
order=()
visit() {
  local key=${1//-/_} dep deps
  [[ -n ${seen[$key]:-} ]] && return 0
  seen[$key]=1
  if [[ -z ${modpath[$key]:-} ]]; then
    [[ -n ${builtin[$key]:-} ]] && return 0
    die "module $1 is neither in $kpkg nor built in"
  fi
  deps=$(modinfo -F depends "${modpath[$key]}")
  for dep in ${deps//,/ }; do visit "$dep"; done
  order+=("$key")
}
for m in "${ROOT_MODULES[@]}"; do visit "$m"; done
log "modules (load order): ${order[*]}"

# The bzImage's payload is one xz stream: unpacked, it is an ELF vmlinux with a PVH entry note.
vmlinuz=$work/pkg/boot/vmlinuz-$kver
off=$(LC_ALL=C grep -obUaP '\xFD7zXZ\x00' "$vmlinuz" | head -n1 | cut -d: -f1)
[[ -n $off ]] || die "no xz payload in vmlinuz-$kver (kernel no longer xz-compressed?)"
xz -dc --single-stream < <(tail -c +$((off + 1)) "$vmlinuz") > "$work/vmlinux" \
  || die "cannot unpack vmlinuz-$kver"
[[ $(head -c 4 "$work/vmlinux" | od -An -c | tr -d ' ') == 177ELF ]] || die "unpacked kernel is no ELF"

# Drop a module's appended signature ("~Module signature appended~\n" after a 12-byte
# struct module_signature whose last 4 bytes are the big-endian signature length).
unsign() {
  local f=$1 size n b
  size=$(stat -c %s "$f")
  [[ $(tail -c 28 "$f") == '~Module signature appended~' ]] || return 0
  n=0
  for b in $(od -An -tu1 -j $((size - 32)) -N 4 "$f"); do n=$((n * 256 + b)); done
  truncate -s $((size - 28 - 12 - n)) "$f"
}

# --- 4. initramfs ------------------------------------------------------------------------------
ird="$work/initramfs"
mkdir -p "$ird"/{bin,sbin,dev,proc,sys,tmp,job,host,etc/hil-vm,lib/modules}
cp /bin/busybox "$ird/bin/busybox"
for a in $("$ird/bin/busybox" --list); do
  [[ $a == busybox ]] || ln -sf busybox "$ird/bin/$a"
done
: > "$ird/etc/hil-vm/modules"
for key in "${order[@]}"; do
  cp "${modpath[$key]}" "$ird/lib/modules/$key.ko"
  unsign "$ird/lib/modules/$key.ko"
  echo "$key" >> "$ird/etc/hil-vm/modules"
done
echo "$kver" > "$ird/etc/hil-vm/kernel"
cat > "$ird/init" <<'EOF'
#!/bin/sh
# Stage 1 of the hil vcan guest (written by tests/vm/prepare.sh): load the modules, mount the
# per-run share "hiljob" and run the guest-init.sh that run-in-vm.sh put there.
export PATH=/bin:/sbin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
fail() { echo "hil-vm init: $*" > /dev/console; sync; poweroff -f; }
while read -r m; do
  insmod "/lib/modules/$m.ko" || fail "insmod $m failed"
done < /etc/hil-vm/modules
mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144,cache=none hiljob /job \
  || fail "cannot mount the 9p share hiljob"
[ -f /job/guest-init.sh ] || fail "/job/guest-init.sh missing"
exec /bin/sh /job/guest-init.sh
EOF
chmod 755 "$ird/init"
(cd "$ird" && find . -print0 | LC_ALL=C sort -z | cpio --null -o -H newc --quiet) \
  | gzip -6 > "$work/initramfs.cpio.gz"

# --- 5. install into the cache -----------------------------------------------------------------
rm -f "$DIR/stamp"
cp "$vmlinuz" "$DIR/vmlinuz.new"
mv "$work/vmlinux" "$DIR/vmlinux.new"
mv "$work/initramfs.cpio.gz" "$DIR/initramfs.cpio.gz.new"
mv "$DIR/vmlinuz.new" "$DIR/vmlinuz"
mv "$DIR/vmlinux.new" "$DIR/vmlinux"
mv "$DIR/initramfs.cpio.gz.new" "$DIR/initramfs.cpio.gz"
echo "$kver" > "$DIR/kernel-release"
printf '%s\n' "${order[@]}" > "$DIR/modules"
echo "$want" > "$DIR/stamp"
log "ready: $DIR (kernel $kver, initramfs $(du -k "$DIR/initramfs.cpio.gz" | cut -f1) KiB)"
