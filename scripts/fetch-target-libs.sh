#!/usr/bin/env bash
# Unpacks the board-side libraries Epipole links (Debian's :arm64 and :armhf packages of
# yaml-cpp and libgpiod) into a cache folder that the cross toolchain files add to their search
# path. Nothing is installed for the foreign architecture: the packages are downloaded with
# apt-get download and unpacked with dpkg-deb. Idempotent.
#
#   scripts/fetch-target-libs.sh arm64|armhf ...
#   EPIPOLE_TARGET_LIBS_DIR   parent folder (default: ${XDG_CACHE_HOME:-~/.cache}/epipole)
set -euo pipefail

packages=(libyaml-cpp-dev libyaml-cpp0.7 libgpiod-dev libgpiod2)
parent=${EPIPOLE_TARGET_LIBS_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole}
sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi

# A failed refresh (a mirror mid-sync) is not fatal when the lists already hold the packages;
# the download below says so if they do not.
refresh_lists() {
  $sudo apt-get update -qq || echo "fetch-target-libs: apt-get update failed; trying the lists as they are" >&2
}

for arch in "$@"; do
  case $arch in
    arm64 | armhf) ;;
    *)
      echo "fetch-target-libs: unknown architecture '$arch' (expected arm64 or armhf)" >&2
      exit 2
      ;;
  esac
  root="$parent/target-libs-$arch"
  stamp="$root/.complete-v1"
  if [[ -f $stamp ]]; then
    echo "fetch-target-libs: $root is complete"
    continue
  fi
  # apt-get download of a foreign architecture needs it known to dpkg and its package lists.
  if ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
    $sudo dpkg --add-architecture "$arch"
    refresh_lists
  fi
  work=$(mktemp -d)
  (
    cd "$work"
    if ! apt-get download -q "${packages[@]/%/:$arch}" >/dev/null 2>&1; then
      refresh_lists
      apt-get download -q "${packages[@]/%/:$arch}" >/dev/null
    fi
    rm -rf "$root.partial"
    mkdir -p "$root.partial"
    for deb in ./*.deb; do
      dpkg-deb -x "$deb" "$root.partial"
      dpkg-deb -f "$deb" Package Version Architecture | paste -sd' ' >>"$root.partial/.complete-v1"
    done
  )
  rm -rf "$work" "$root"
  mv "$root.partial" "$root"
  echo "fetch-target-libs: $root ready"
done
