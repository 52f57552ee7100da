#!/usr/bin/env bash
# Makes the deployment test's board (docs/deploy.md): a Debian bookworm arm64 root filesystem
# from Debian's packages, as a disk image that boots with systemd under qemu-system-aarch64, and
# the small initramfs that mounts it. Cached by release and kernel: made once, then every test
# boots a copy-on-write overlay of it.
#
#   scripts/deploy/make-rootfs.sh
#
# debootstrap's first stage runs here (downloads and unpacks); its second stage runs the
# packages' maintainer scripts, arm64 programs, so it runs in the guest: this machine has no
# binfmt_misc to run them through qemu-user. The kernel is the virtual board's
# (scripts/vboard/fetch-kernel.sh, build-modules.sh): its modules for virtio, the cameras, the
# trigger line and the serial adapters go into the image.
#
# The cache folder ($(deploy_cache)/bookworm-arm64-KVER/):
#   rootfs.img      the root filesystem, ext4, raw (the tests' overlays are qcow2 on top of it)
#   initramfs.cpio  busybox and the modules that find and mount it (tests/deploy/guest/init)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/../vboard/common.sh"
source "$here/common.sh"
guest="$here/../../tests/deploy/guest"

if [[ $(id -u) -ne 0 ]]; then
  echo "make-rootfs: debootstrap must run as root (it makes device nodes and owns files)" >&2
  exit 1
fi
EPIPOLE_VBOARD_KVER=$(vboard_kernel_version arm64)
export EPIPOLE_VBOARD_KVER
kver=$EPIPOLE_VBOARD_KVER
out=$(deploy_rootfs_dir "$kver")
stamp="$out/.complete-v2"  # v2: the init waits for its console to open
if [[ -f $stamp ]]; then
  echo "make-rootfs: $out is complete"
  exit 0
fi
start=$SECONDS
"$here/../vboard/fetch-kernel.sh" arm64
"$here/../vboard/build-modules.sh" arm64
kernel=$(vboard_cache "$kver")

rm -rf "$out.partial"
mkdir -p "$out.partial"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rootfs="$work/rootfs"

# First stage: Debian's minimal system, systemd as init, udev, and what the package's scripts
# and the test use. The mirror is the one apt here uses.
mirror=$(apt-cache policy | awk '$3 ~ /^bookworm\/main$/ {print $2; exit}')
[[ -n $mirror ]] || mirror=http://deb.debian.org/debian
echo "make-rootfs: debootstrap bookworm arm64 from $mirror (first stage)"
debootstrap --foreign --arch=arm64 --variant=minbase \
  --include=systemd-sysv,udev,kmod,adduser,procps bookworm "$rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 || {
  tail -20 "$work/debootstrap.log" >&2
  exit 1
}

# The kernel's modules the board needs, with their dependencies (kmod resolves them on the
# unpacked kernel); a modules.dep made here, as the kernel package's postinst would.
modules="$rootfs/lib/modules/$kver"
mkdir -p "$modules/extra"
deploy_module_closure "$kernel/image" "$kver" virtio_pci virtio_blk crc32c_generic ext4 virtio_console vivid \
  configfs videodev usbserial cdc_acm | while read -r ko; do
  relative=${ko#"$kernel/image/lib/modules/$kver/"}
  mkdir -p "$modules/$(dirname "$relative")"
  cp "$ko" "$modules/$relative"
done
cp "$kernel/modules/gpio-sim.ko" "$modules/extra/"
cp "$kernel/image/lib/modules/$kver"/modules.{builtin,builtin.modinfo,order} "$modules/"
depmod -b "$rootfs" "$kver"

# The board's own set-up: its name, no network, the console on the virtio console (the PL011 is
# left to the board file's UART), and the test's runner, started from the test's disk.
echo epipole-deploy >"$rootfs/etc/hostname"
printf '127.0.0.1 localhost\n127.0.1.1 epipole-deploy\n' >"$rootfs/etc/hosts"
printf '/dev/vda / ext4 defaults 0 1\n' >"$rootfs/etc/fstab"
rm -f "$rootfs/etc/apt/sources.list"
install -m 0755 "$guest/second-stage.sh" "$rootfs/second-stage.sh"
install -m 0644 "$guest/epipole-deploy-test.service" "$rootfs/etc/systemd/system/"

# The initramfs: busybox, the modules that reach the disk and the console, and its init.
stage="$work/initramfs"
mkdir -p "$stage/bin" "$stage/newroot"
cp "$kernel/busybox" "$stage/bin/busybox"
cp "$guest/init" "$stage/init"
chmod 0755 "$stage/init"
deploy_module_closure "$kernel/image" "$kver" virtio_pci virtio_blk crc32c_generic ext4 virtio_console |
  while read -r ko; do
    relative=${ko#"$kernel/image/"}
    mkdir -p "$stage/$(dirname "$relative")"
    cp "$ko" "$stage/$relative"
  done
cp "$kernel/image/lib/modules/$kver"/modules.{builtin,builtin.modinfo,order} "$stage/lib/modules/$kver/"
depmod -b "$stage" "$kver"
(cd "$stage" && find . -print0 | sort -z | cpio --null -o -H newc -R 0:0 --quiet) >"$out.partial/initramfs.cpio"

# The disk: 3 GiB of ext4 (sparse), filled from the folder with owners and modes kept.
echo "make-rootfs: disk image"
mke2fs -q -t ext4 -L epipole-root -d "$rootfs" "$out.partial/rootfs.img" 3G

# Second stage, in the guest: debootstrap configures every package, then the guest's own
# set-up (tests/deploy/guest/second-stage.sh) runs, and the guest powers off.
# A guest that stops before its console says a word (seen under heavy load: QEMU exits at once,
# status 0, the console empty: the kernel gave up before the virtio console was there) is
# booted again from the image as the first stage left it, up to three times; any other failure
# is reported with the console's end. Idle it takes about 5.5 minutes; beside a build (as
# scripts/run-tests.sh makes it) about twice that, hence the generous limit.
echo "make-rootfs: second stage in the guest (emulated arm64)"
phase=$SECONDS
console="$out.partial/second-stage.log"
cp --sparse=always "$out.partial/rootfs.img" "$work/first-stage.img"
for attempt in 1 2 3; do
  status=0
  timeout 1800 "$here/boot.sh" "$out.partial" "$out.partial/rootfs.img" "" \
    deploy.stage=second >"$console" 2>&1 </dev/null || status=$?
  grep -q "deploy: second stage done" "$console" && break
  if [[ ! -s $console ]] && ((attempt < 3)); then
    echo "make-rootfs: the guest stopped before its console started (status $status," \
      "attempt $attempt); booting it again" >&2
    cp --sparse=always "$work/first-stage.img" "$out.partial/rootfs.img"
    continue
  fi
  echo "make-rootfs: the second stage failed (status $status); the guest's console:" >&2
  tail -40 "$console" >&2
  exit 1
done
echo "make-rootfs: second stage took $((SECONDS - phase)) s"

echo "$kver" >"$out.partial/kernel-version"
rm -rf "$out"
mv "$out.partial" "$out"
touch "$stamp"
echo "make-rootfs: $out ready in $((SECONDS - start)) s ($(du -h "$out/rootfs.img" | cut -f1) used)"
