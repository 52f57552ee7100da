#!/usr/bin/env bash
# Builds the .deb of a configured build folder with cpack and checks what is in it: the
# architecture, the dependencies (computed by dpkg-shlibdeps: every library the firmware needs
# is a versioned dependency), the firmware binary for that architecture (and that it runs:
# under qemu-user for a cross build), the unit, the udev rules, the board files, the maintainer
# scripts, the conffile, the copyright file and the changelog; and that lintian finds no error.
#
#   scripts/check-package.sh BUILD_DIR DEBIAN_ARCH      e.g. build/aarch64 arm64
set -euo pipefail
build=$1
arch=$2
# The target's libraries (scripts/fetch-target-libs.sh) this build linked, for a cross build.
target_libs=$(sed -n 's/^EPIPOLE_TARGET_LIBS:PATH=//p' "$build/CMakeCache.txt")
case $arch in
  arm64) machine=AArch64 triple=aarch64-linux-gnu emulator=qemu-aarch64 ;;
  armhf) machine=ARM triple=arm-linux-gnueabihf emulator=qemu-arm ;;
  amd64) machine=X86-64 qemu=() ;;
  *) echo "check-package: unknown architecture $arch" >&2; exit 2 ;;
esac
if [[ $arch != amd64 ]]; then
  qemu=("$emulator" -L "/usr/$triple"
    -E "LD_LIBRARY_PATH=$target_libs/usr/lib/$triple:$target_libs/lib/$triple")
fi

fail() {
  echo "check-package: $*" >&2
  exit 1
}

(cd "$build" && rm -f epipole_*.deb && cpack -G DEB >/dev/null)
deb=$(ls "$build"/epipole_*_"$arch".deb 2>/dev/null | head -1)
[[ -n $deb ]] || fail "cpack made no epipole_*_$arch.deb in $build"

[[ $(dpkg-deb -f "$deb" Architecture) == "$arch" ]] || fail "$deb: architecture is not $arch"
depends=$(dpkg-deb -f "$deb" Depends)
for p in 'libc6 (>= ' 'libstdc++6 (>= ' 'libgcc-s1 (>= ' adduser init-system-helpers; do
  grep -qF "$p" <<<"$depends" || fail "$deb: Depends has no '$p': $depends"
done

contents=$(dpkg-deb -c "$deb" | awk '{print $6}')
for f in ./usr/bin/epipole-fw ./usr/lib/systemd/system/epipole.service \
  ./usr/lib/udev/rules.d/60-epipole.rules ./usr/lib/modules-load.d/epipole.conf \
  ./etc/epipole/board.yaml \
  ./usr/share/epipole/board/sim/board.yaml ./usr/share/epipole/board/raspberrypi5-ov9281/board.yaml \
  ./usr/share/epipole/board/usb-stereo/board.yaml ./usr/share/doc/epipole/README.md \
  ./usr/share/doc/epipole/copyright ./usr/share/doc/epipole/changelog.gz \
  ./usr/share/man/man1/epipole-fw.1.gz; do
  grep -qxF "$f" <<<"$contents" || fail "$deb: $f is missing"
done

control=$(mktemp -d)
trap 'rm -rf "$control"' EXIT
dpkg-deb -e "$deb" "$control/DEBIAN"
for f in postinst prerm postrm conffiles; do
  [[ -f $control/DEBIAN/$f ]] || fail "$deb: control file $f is missing"
done
grep -qx /etc/epipole/board.yaml "$control/DEBIAN/conffiles" || fail "$deb: board.yaml is no conffile"
for f in postinst prerm postrm; do
  sh -n "$control/DEBIAN/$f" || fail "$deb: $f is not valid sh"
done

dpkg-deb -x "$deb" "$control/root"
fw="$control/root/usr/bin/epipole-fw"
readelf -h "$fw" | grep -q "Machine:.*$machine" || fail "$deb: epipole-fw is not an $machine binary"
# The manual page is the target program's own --help (made under qemu-user in a cross build).
zcat "$control/root/usr/share/man/man1/epipole-fw.1.gz" | grep -qF -- '\-\-board' ||
  fail "$deb: the manual page of epipole-fw does not describe --board"
grep -q '^Type=notify' "$control/root/usr/lib/systemd/system/epipole.service" ||
  fail "$deb: the unit is not Type=notify"
# The unit's sandbox: systemd's exposure score (0 safe .. 10 unsafe) at most 2.5.
unit="$control/root/usr/lib/systemd/system/epipole.service"
security=$(systemd-analyze security --offline=true --threshold=25 "$unit" 2>&1) ||
  fail "$deb: the unit's exposure is above 2.5: $(tail -1 <<<"$security")"
exposure=$(sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]* [A-Z]*\).*/\1/p' <<<"$security")
version=$("${qemu[@]}" "$fw" --version) || fail "$deb: epipole-fw --version did not run"
# Every library the firmware needs comes from a package it depends on.
depends_names=$(sed 's/ ([^)]*)//g; s/, /\n/g' <<<"$depends")
for lib in $(LC_ALL=C readelf -d "$fw" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
  if [[ $arch == amd64 ]]; then
    owner=$(dpkg-query -S "*/$(gcc -dumpmachine)/$lib" 2>/dev/null | head -1 || true)
  else
    owner=$(dpkg-query --admindir="$target_libs/dpkg" -S "*/$lib" 2>/dev/null | head -1 || true)
  fi
  package=${owner%%:*}
  [[ -n $package ]] || fail "$deb: no package of $arch holds $lib (NEEDED by epipole-fw)"
  grep -qxF "$package" <<<"$depends_names" || fail "$deb: needs $lib of $package, not in Depends: $depends"
done
# The Raspberry Pi 5 board file the package installs selects libcamera: a firmware built
# without it could not start on that board.
LC_ALL=C readelf -d "$fw" | grep -q 'NEEDED.*\[libcamera\.so' ||
  fail "$deb: epipole-fw is built without libcamera (the Raspberry Pi 5 board file needs it)"
changelog=$(zcat "$control/root/usr/share/doc/epipole/changelog.gz" | head -1)
[[ $changelog == "epipole ($(dpkg-deb -f "$deb" Version))"* ]] ||
  fail "$deb: the changelog's last entry is not this version: $changelog"
# Errors fail; warnings (no manual pages yet) are shown.
lint_status=0
lint=$(lintian --fail-on error --tag-display-limit 0 "$deb" 2>&1) || lint_status=$?
grep -v 'root privileges' <<<"$lint" || true
((lint_status == 0)) || fail "$deb: lintian reports errors (above)"
echo "check-package: $deb ok ($(du -k "$deb" | cut -f1) KiB; $version; exposure $exposure)"
