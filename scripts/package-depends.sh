#!/usr/bin/env bash
# Prints the Debian dependencies of a package's binaries, computed by dpkg-shlibdeps from the
# libraries they link against those of the package's architecture: for the host, the installed
# packages; for a cross architecture, the database scripts/fetch-target-libs.sh made beside the
# target's libraries. Output: dpkg-shlibdeps' variables, one a line, e.g.
# "shlibs:Depends=libc6 (>= 2.34), libstdc++6 (>= 12)".
#
#   scripts/package-depends.sh ARCH [--target-libs DIR] FILE... [-dRecommends FILE...]
#   DIR: the target's libraries (default: ${XDG_CACHE_HOME:-~/.cache}/epipole/target-libs-ARCH)
set -euo pipefail

usage="usage: scripts/package-depends.sh ARCH [--target-libs DIR] FILE... [-dRecommends FILE...]"
arch=${1:?$usage}
shift
root=${XDG_CACHE_HOME:-$HOME/.cache}/epipole/target-libs-$arch
if [[ ${1:-} == --target-libs ]]; then
  root=${2:?$usage}
  shift 2
fi
(($# > 0)) || { echo "$usage" >&2; exit 2; }
options=()
if [[ $arch != "$(dpkg --print-architecture)" ]]; then
  if [[ ! -d $root/dpkg ]]; then
    echo "package-depends: no $root/dpkg: run scripts/fetch-target-libs.sh $arch" >&2
    exit 1
  fi
  triple=$(dpkg-architecture -a"$arch" -qDEB_HOST_MULTIARCH 2>/dev/null)
  export DEB_HOST_ARCH=$arch
  options=(--admindir="$root/dpkg" -l"$root/usr/lib/$triple" -l"$root/lib/$triple"
    -l"/usr/$triple/lib")
fi

# dpkg-shlibdeps works in a source package's tree: a minimal one, the binaries in its package
# folder.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/debian/epipole/DEBIAN" "$work/debian/epipole/bin"
printf 'Source: epipole\n\nPackage: epipole\nArchitecture: any\n' >"$work/debian/control"
arguments=()
for a in "$@"; do
  if [[ $a == -d* ]]; then
    arguments+=("$a")
  else
    copy="debian/epipole/bin/$(basename "$a")"
    cp "$a" "$work/$copy"
    arguments+=("-e$copy")
  fi
done
(cd "$work" && dpkg-shlibdeps -O "${options[@]}" "${arguments[@]}")
