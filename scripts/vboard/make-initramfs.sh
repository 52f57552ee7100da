#!/usr/bin/env bash
# Makes the virtual board's initramfs: busybox, the kernel modules of the cameras and the
# trigger line, the firmware of a build folder with the shared libraries it needs, the guest's
# helpers, the board file and its init. fetch-kernel.sh and build-modules.sh come first.
#
#   scripts/vboard/make-initramfs.sh amd64|arm64 BUILD_DIR OUTPUT.cpio
#
# BUILD_DIR is a build of the guest's architecture (build/host for amd64, build/aarch64 for
# arm64) with the targets epipole-fw, vboard-trigger and vboard-control.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
arch=${1:?usage: make-initramfs.sh amd64|arm64 BUILD_DIR OUTPUT.cpio}
build=${2:?usage: make-initramfs.sh amd64|arm64 BUILD_DIR OUTPUT.cpio}
output=${3:?usage: make-initramfs.sh amd64|arm64 BUILD_DIR OUTPUT.cpio}
vboard_check_arch "$arch"
board="$here/../../board/vboard"

kver=$(vboard_kernel_version "$arch")
root=$(vboard_cache "$kver")
[[ -f $root/modules/gpio-sim.ko ]] || {
  echo "make-initramfs: $root/modules is missing: run fetch-kernel.sh and build-modules.sh $arch" >&2
  exit 1
}
for program in firmware/epipole-fw tests/vboard/vboard-trigger tests/vboard/vboard-control; do
  [[ -x $build/$program ]] || {
    echo "make-initramfs: $build/$program is missing (build it first)" >&2
    exit 1
  }
done
cross=$(vboard_cross_prefix "$arch")
if [[ -n $cross ]]; then
  triple=aarch64-linux-gnu
  # The cross toolchain's C and C++ runtime, then the target's libraries the build linked
  # (libcamera and what it needs: scripts/fetch-target-libs.sh).
  target_libs=$(sed -n 's/^EPIPOLE_TARGET_LIBS:PATH=//p' "$build/CMakeCache.txt")
  [[ -n $target_libs ]] || {
    echo "make-initramfs: $build/CMakeCache.txt names no EPIPOLE_TARGET_LIBS" >&2
    exit 1
  }
  library_dirs=(/usr/$triple/lib "$target_libs/usr/lib/$triple" "$target_libs/lib/$triple")
else
  triple=$(gcc -dumpmachine)
  library_dirs=(/lib/$triple /usr/lib/$triple)
fi

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage"/{bin,usr/bin,etc/epipole,proc,sys,dev,tmp,run,lib/"$triple"}
cp "$root/busybox" "$stage/bin/busybox"
ln -s busybox "$stage/bin/sh"
cp "$board/init" "$stage/init"
cp "$board/board.yaml" "$board/board-libcamera.yaml" "$stage/etc/epipole/"
cp "$build/tests/vboard/vboard-trigger" "$build/tests/vboard/vboard-control" "$stage/usr/bin/"

# A dynamically linked program and, recursively, the libraries it names (DT_NEEDED), from the
# guest architecture's library folders; its loader where PT_INTERP says.
add_program() {
  local program=$1 interp lib dir found
  "${cross}strip" --strip-debug -o "$stage/usr/bin/$(basename "$program")" "$program"
  interp=$(LC_ALL=C "${cross}readelf" -l "$program" | sed -n 's/.*Requesting program interpreter: \(.*\)]/\1/p')
  if [[ -n $interp ]]; then
    mkdir -p "$stage$(dirname "$interp")"
    cp -L "$(find "${library_dirs[@]}" -maxdepth 1 -name "$(basename "$interp")" | head -1)" "$stage$interp"
  fi
  local pending=("$program")
  while ((${#pending[@]} > 0)); do
    local next=("${pending[@]}")
    pending=()
    for file in "${next[@]}"; do
      for lib in $(LC_ALL=C "${cross}readelf" -d "$file" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
        [[ -e $stage/lib/$triple/$lib ]] && continue
        found=
        for dir in "${library_dirs[@]}"; do
          [[ -e $dir/$lib ]] && found=$dir/$lib && break
        done
        [[ -n $found ]] || {
          echo "make-initramfs: $lib (needed by $file) is not in ${library_dirs[*]}" >&2
          exit 1
        }
        cp -L "$found" "$stage/lib/$triple/$lib"
        pending+=("$found")
      done
    done
  done
}
add_program "$build/firmware/epipole-fw"

# A firmware built with libcamera gets the vimc pipeline's IPA module (Debian's libcamera-ipa of
# the same version as the libcamera it links, fetched once into the cache): the libcamera test
# runs on two vimc cameras (board-libcamera.yaml).
if "${cross}readelf" -d "$build/firmware/epipole-fw" | grep -q 'NEEDED.*\[libcamera\.so'; then
  [[ -n $cross ]] && qualifier=":arm64" || qualifier=""
  version=$(dpkg-query -W -f='${Version}' "libcamera0.0.3$qualifier" 2>/dev/null ||
    vboard_package_version "libcamera0.0.3$qualifier")
  ipa=$(vboard_cache "libcamera-ipa-$version-$arch")
  if [[ ! -d $ipa ]]; then
    download=$(mktemp -d)
    (cd "$download" && vboard_download "libcamera-ipa$qualifier=$version")
    dpkg-deb -x "$download"/libcamera-ipa_*.deb "$ipa.partial"
    rm -rf "$download"
    mv "$ipa.partial" "$ipa"
  fi
  for file in usr/lib/$triple/libcamera/{ipa_vimc.so,ipa_vimc.so.sign,vimc_ipa_proxy} \
    usr/share/libcamera/ipa/vimc/vimc.conf; do
    mkdir -p "$stage/$(dirname "$file")"
    cp "$ipa/$file" "$stage/$file"
  done
fi

# Kernel modules: what vivid, configfs and the USB serial link need (kmod resolves the closure
# on the unpacked kernel), the two built out of tree, and a modules.dep for busybox's modprobe.
modules="$stage/lib/modules/$kver"
mkdir -p "$modules/extra"
for module in vivid configfs xhci-pci ftdi_sio; do
  modprobe -d "$root/image" -S "$kver" --show-depends "$module" | awk '$1 == "insmod" {print $2}'
done | sort -u | while read -r ko; do
  relative=${ko#"$root/image/lib/modules/$kver/"}
  mkdir -p "$modules/$(dirname "$relative")"
  cp "$ko" "$modules/$relative"
done
cp "$root/modules/gpio-sim.ko" "$root/modules/vimc.ko" "$modules/extra/"
cp "$root/image/lib/modules/$kver"/modules.{builtin,builtin.modinfo,order} "$modules/"
depmod -b "$stage" "$kver"

mkdir -p "$(dirname "$output")"
(cd "$stage" && find . -print0 | sort -z | cpio --null -o -H newc -R 0:0 --quiet) >"$output.partial"
mv "$output.partial" "$output"
echo "make-initramfs: $output ($(du -h "$output" | cut -f1), kernel $kver)"
