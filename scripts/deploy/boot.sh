#!/usr/bin/env bash
# Boots the deployment test's board: the virtual board's arm64 kernel with the initramfs of
# ROOTFS_DIR (make-rootfs.sh), DISK as the root filesystem (/dev/vda: the image itself, or a
# qcow2 overlay of it) and PAYLOAD, when given, as the test's disk (/dev/vdb, read-only), under
# qemu-system-aarch64 (TCG, the virt machine, two Cortex-A72, 1 GiB).
#
#   scripts/deploy/boot.sh ROOTFS_DIR DISK [PAYLOAD] [KERNEL ARGUMENTS...]
#
# The console (the virtio console, guest /dev/hvc0) is this program's standard output.
#   EPIPOLE_DEPLOY_LINK=socket:PATH   the board file's link UART, a PCI 16550 (guest /dev/ttyS0),
#                                     on a unix socket; QEMU waits for the host to connect
#   EPIPOLE_DEPLOY_UART0=PATH         the PL011 (guest /dev/ttyAMA0, the Raspberry Pi board
#                                     file's UART) written to a file (default: nowhere)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/../vboard/common.sh"
usage="usage: boot.sh ROOTFS_DIR DISK [PAYLOAD] [KERNEL ARGUMENTS...]"
rootfs=${1:?$usage}
disk=${2:?$usage}
payload=${3:-}
shift 2
[[ $# -gt 0 ]] && shift
kver=$(cat "$rootfs/kernel-version" 2>/dev/null || vboard_kernel_version arm64)
kernel=$(vboard_cache "$kver")/image/boot/vmlinuz-$kver
[[ -f $kernel ]] || {
  echo "boot: no kernel $kernel (scripts/vboard/fetch-kernel.sh arm64)" >&2
  exit 1
}
format=raw
[[ $(head -c 4 "$disk" | od -An -c | tr -d ' ') == QFI* ]] && format=qcow2

devices=(-drive "file=$disk,if=none,id=root,format=$format,cache=unsafe"
  -device virtio-blk-pci,drive=root)
if [[ -n $payload ]]; then
  devices+=(-drive "file=$payload,if=none,id=payload,format=raw,readonly=on"
    -device virtio-blk-pci,drive=payload)
fi
case ${EPIPOLE_DEPLOY_LINK:-none} in
  none) ;;
  socket:*)
    devices+=(-chardev "socket,id=link,path=${EPIPOLE_DEPLOY_LINK#socket:},server=on,wait=on"
      -device pci-serial,chardev=link)
    ;;
  *)
    echo "boot: EPIPOLE_DEPLOY_LINK must be socket:PATH, not '$EPIPOLE_DEPLOY_LINK'" >&2
    exit 2
    ;;
esac
if [[ -n ${EPIPOLE_DEPLOY_UART0:-} ]]; then
  devices+=(-chardev "file,id=uart0,path=$EPIPOLE_DEPLOY_UART0" -serial chardev:uart0)
else
  devices+=(-serial null)
fi

exec qemu-system-aarch64 -M virt -cpu cortex-a72 -accel tcg,thread=multi -smp 2 -m 1024 \
  -nodefaults -no-user-config -display none -no-reboot \
  -device virtio-serial-pci -chardev stdio,id=console,signal=off -device virtconsole,chardev=console \
  "${devices[@]}" -kernel "$kernel" -initrd "$rootfs/initramfs.cpio" \
  -append "console=hvc0 quiet panic=-1 systemd.show_status=false $*"
