#!/usr/bin/env bash
# Boots the virtual board: Debian's kernel (fetch-kernel.sh) with an initramfs
# (make-initramfs.sh) under qemu-system, emulated (TCG). The console is this program's
# standard input and output; the guest's second UART, the firmware's link, is wired to the host.
#
#   scripts/vboard/boot.sh amd64|arm64 INITRAMFS [KERNEL ARGUMENTS...]
#
#   EPIPOLE_VBOARD_UART=pty           the link on a pseudo-terminal (QEMU prints its path)
#   EPIPOLE_VBOARD_UART=socket:PATH   the link on a unix socket; QEMU waits for the host to
#                                     connect before the guest starts, so no byte is lost
#   EPIPOLE_VBOARD_LINK=uart          the link on a 16550 UART (default): the guest cannot tell
#                                     whether the host is there
#   EPIPOLE_VBOARD_LINK=usb           the link on a USB serial adapter (an FTDI on an xHCI
#                                     controller, guest /dev/ttyUSB0) that QEMU unplugs while the
#                                     host end is closed, as a robot's cable pulled out
#
# amd64: the PC machine booting the uncompressed kernel (PVH), the UART a 16550 at 0x2f8 (guest
#        /dev/ttyS1).
# arm64: the virt machine with a Cortex-A72 (its one PL011 is the console), the UART a PCI
#        16550 (guest /dev/ttyS0).
# KVM is not used: where /dev/kvm is a nested or paravirtual flavour it cannot run a stock
# kernel, and TCG boots in seconds.
set -euo pipefail
source "$(dirname "$0")/common.sh"
arch=${1:?usage: boot.sh amd64|arm64 INITRAMFS [KERNEL ARGUMENTS...]}
initramfs=${2:?usage: boot.sh amd64|arm64 INITRAMFS [KERNEL ARGUMENTS...]}
shift 2
vboard_check_arch "$arch"
# The kernel the initramfs was made for: its modules' folder says which.
kver=$(cpio -t --quiet <"$initramfs" | sed -n 's|^\(\./\)\{0,1\}lib/modules/\([^/]*\)$|\2|p')
kver=${kver%%$'\n'*}
[[ -n $kver ]] || {
  echo "boot: $initramfs has no lib/modules/VERSION (make it with make-initramfs.sh)" >&2
  exit 1
}
root=$(vboard_cache "$kver")

uart=${EPIPOLE_VBOARD_UART:-pty}
case $uart in
  pty) chardev="pty,id=link" ;;
  socket:*) chardev="socket,id=link,path=${uart#socket:},server=on,wait=on" ;;
  *)
    echo "boot: EPIPOLE_VBOARD_UART must be pty or socket:PATH, not '$uart'" >&2
    exit 2
    ;;
esac

# The link: each machine's UART, or the same USB serial adapter on both.
if [[ $arch == amd64 ]]; then
  link=(-device isa-serial,chardev=link) guest=/dev/ttyS1
else
  link=(-device pci-serial,chardev=link) guest=/dev/ttyS0
fi
case ${EPIPOLE_VBOARD_LINK:-uart} in
  uart) ;;
  usb) link=(-device qemu-xhci -device usb-serial,chardev=link) guest=/dev/ttyUSB0 ;;
  *)
    echo "boot: EPIPOLE_VBOARD_LINK must be uart or usb, not '$EPIPOLE_VBOARD_LINK'" >&2
    exit 2
    ;;
esac

common=(-accel tcg -m 512 -smp ${EPIPOLE_VBOARD_CPUS:-1} -nodefaults -no-user-config -display none -no-reboot
  -serial stdio -chardev "$chardev" -initrd "$initramfs" "${link[@]}")
if [[ $arch == amd64 ]]; then
  exec qemu-system-x86_64 -M pc -cpu max "${common[@]}" -kernel "$root/vmlinux" \
    -append "console=ttyS0 quiet panic=-1 epipole.uart=$guest $*"
else
  exec qemu-system-aarch64 -M virt -cpu cortex-a72 "${common[@]}" \
    -kernel "$root/image/boot/vmlinuz-$kver" \
    -append "console=ttyAMA0 quiet panic=-1 epipole.uart=$guest $*"
fi
