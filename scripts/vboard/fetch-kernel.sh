#!/usr/bin/env bash
# Fetches Debian's kernel for the virtual board's architecture, and what building modules for it
# needs, into the cache folder of that kernel version. Nothing is installed: the packages are
# downloaded and unpacked. Idempotent: a complete folder is left as it is.
#
#   scripts/vboard/fetch-kernel.sh amd64|arm64
#
# The folder ($(vboard_cache KVER)):
#   image/     linux-image-KVER unpacked, with the modules.dep the package's postinst would make
#   headers/   linux-headers-KVER, its -common part and the host's linux-kbuild (out-of-tree builds)
#   vmlinux    amd64: the uncompressed kernel (booted through its PVH entry)
#   busybox    the static busybox of the guest architecture (the initramfs's shell and tools)
# and beside it linux-source-VERSION/: the few driver sources build-modules.sh needs.
set -euo pipefail
source "$(dirname "$0")/common.sh"
arch=${1:?usage: fetch-kernel.sh amd64|arm64}
vboard_check_arch "$arch"

kver=$(vboard_kernel_version "$arch")
abi=${kver%-"$arch"}
root=$(vboard_cache "$kver")
stamp="$root/.complete-v1"
if [[ -f $stamp ]]; then
  echo "fetch-kernel: $root is complete"
  exit 0
fi
host_arch=$(dpkg --print-architecture)
version=$(vboard_package_version "linux-image-$kver:$arch")
echo "fetch-kernel: linux-image-$kver $version ($arch)"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
vboard_download "linux-image-$kver:$arch=$version" "linux-headers-$kver:$arch=$version" \
  "linux-headers-$abi-common=$version" "linux-kbuild-6.1:$host_arch=$version" \
  "busybox-static:$arch"

rm -rf "$root.partial"
mkdir -p "$root.partial/image" "$root.partial/headers" "$root.partial/busybox-package"
dpkg-deb -x linux-image-*.deb "$root.partial/image"
# The package has no modules.dep: its postinst runs depmod. The initramfs's modprobe needs it.
depmod -b "$root.partial/image" "$kver"
for deb in linux-headers-*.deb linux-kbuild-*.deb; do dpkg-deb -x "$deb" "$root.partial/headers"; done
# The headers' Makefile includes its -common part by an absolute path: point it at ours.
sed -i "s|^include /usr/src/|include $root/headers/usr/src/|" \
  "$root.partial/headers/usr/src/linux-headers-$kver/Makefile"
dpkg-deb -x busybox-static_*.deb "$root.partial/busybox-package"
mv "$root.partial/busybox-package/bin/busybox" "$root.partial/busybox"
rm -rf "$root.partial/busybox-package"
if [[ $arch == amd64 ]]; then
  # The uncompressed kernel, booted through its PVH entry: emulated, the bzImage's XZ
  # decompression and real-mode set-up take seconds. Its payload starts at the XZ magic.
  image="$root.partial/image/boot/vmlinuz-$kver"
  offset=$(LC_ALL=C grep -obUaP '\xfd7zXZ\x00' "$image" | head -1 | cut -d: -f1)
  tail -c +$((offset + 1)) "$image" | xz -dc 2>/dev/null >"$root.partial/vmlinux" || true
  [[ $(head -c 4 "$root.partial/vmlinux" | od -An -c | tr -d ' ') == 177ELF ]] || {
    echo "fetch-kernel: no ELF kernel inside $image" >&2
    exit 1
  }
fi
ls ./*.deb | xargs -n1 basename >"$root.partial/.complete-v1"

# Driver sources: gpio-sim (and the interrupt simulator it needs) and vimc, which Debian's
# configuration leaves out. A few files out of linux-source's 140 MB archive. Both architectures'
# kernels share them, and both are prepared at once (ctest -j): one unpacks under a lock, into a
# private folder that is renamed into place when complete.
source_dir=$(vboard_cache "linux-source-$version")
mkdir -p "$(dirname "$source_dir")"
exec {source_lock}>"$source_dir.lock"
flock "$source_lock"
if [[ ! -f $source_dir/.complete-v1 ]]; then
  vboard_download "linux-source-6.1=$version"
  rm -rf "$source_dir" "$source_dir.partial" && mkdir -p "$source_dir.partial"
  dpkg-deb --fsys-tarfile linux-source-6.1_*.deb | tar -xO ./usr/src/linux-source-6.1.tar.xz |
    tar -xJ -C "$source_dir.partial" --strip-components=1 --wildcards \
      linux-source-6.1/drivers/gpio/gpio-sim.c linux-source-6.1/drivers/gpio/gpiolib.h \
      linux-source-6.1/kernel/irq/irq_sim.c 'linux-source-6.1/drivers/media/test-drivers/vimc/*'
  touch "$source_dir.partial/.complete-v1"
  mv "$source_dir.partial" "$source_dir"
fi
flock -u "$source_lock"
echo "$version" >"$root.partial/source-version"

rm -rf "$root"
mv "$root.partial" "$root"
echo "fetch-kernel: $root ready"
