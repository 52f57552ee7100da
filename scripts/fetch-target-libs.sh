#!/usr/bin/env bash
# Unpacks the board-side libraries Epipole links (Debian's :arm64 and :armhf packages of
# yaml-cpp and libgpiod, linked statically, libcamera, CycloneDDS, civetweb, TurboJPEG, libpng, libjpeg and zstd with the libraries
# they need at run time, and for the board's epipole-bench Debian's OpenCV with the libraries it
# loads) into a cache folder that the cross toolchain files add to their search path (and the
# cross-built tests' library path under qemu), and writes a dpkg database of them beside
# (dpkg/), from which scripts/package-depends.sh computes the board package's dependencies. The database also holds Debian's C and C++
# runtime packages of the target (libc6, libstdc++6, libgcc-s1), their files mapped onto the
# cross toolchain's copies of the same libraries in /usr/<triple>/lib, which is what the
# binaries link. Nothing is installed for the foreign architecture: the packages are downloaded
# with apt-get download and unpacked with dpkg-deb. Idempotent.
#
#   scripts/fetch-target-libs.sh arm64|armhf ...
#   EPIPOLE_TARGET_LIBS_DIR   parent folder (default: ${XDG_CACHE_HOME:-~/.cache}/epipole)
set -euo pipefail

packages=(libyaml-cpp-dev libyaml-cpp0.7 libgpiod-dev libgpiod2)
# The recordings' compression (MCAP chunks), linked dynamically.
recording=(libzstd-dev libzstd1)
# The live view's HTTP and WebSocket server and its pictures (TurboJPEG), linked dynamically.
view=(libcivetweb-dev libcivetweb1 libturbojpeg0-dev libturbojpeg0)
# Image files: the firmware replays a simulated board's scenes on a board too.
images=(libpng-dev libpng16-16 libjpeg62-turbo-dev libjpeg62-turbo zlib1g-dev)
# epipole-bench's OpenCV pipeline: the headers and libraries of the modules it uses and of those
# they load (objdetect loads dnn; core loads BLAS/LAPACK, TBB and GLX), without the rest of
# libopencv-dev's closure (Qt, GDAL, FFmpeg, Mesa).
opencv=(libopencv-{core,imgproc,features2d,flann,calib3d,objdetect,dnn}{-dev,406}
  libblas3 liblapack3 libgfortran5 libtbb12 libprotobuf32 zlib1g
  libglx0 libglvnd0 libx11-6 libxcb1 libxau6 libxdmcp6 libbsd0 libmd0)
# Header-only libraries of the bench's command line and JSON (Architecture: all).
headers=(libcli11-dev nlohmann-json3-dev)
runtime=(libc6 libstdc++6 libgcc-s1 gcc-12-base)
parent=${EPIPOLE_TARGET_LIBS_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole}
sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi

# A failed refresh (a mirror mid-sync) is not fatal when the lists already hold the packages;
# the download below says so if they do not.
refresh_lists() {
  $sudo apt-get update -qq || echo "fetch-target-libs: apt-get update failed; trying the lists as they are" >&2
}

# Whether the database says which package each library in the folder comes from, as
# dpkg-shlibdeps will ask it (a folder moved, copied or made by an older version of this script
# names other paths).
database_answers() {
  local lib
  for lib in "$root/usr/lib/$triple"/libcamera.so.[0-9]* "$root/usr/lib/$triple"/libyaml-cpp.so.[0-9]*; do
    [[ -f $lib ]] || return 1
    dpkg-query --admindir="$root/dpkg" -S "$lib" >/dev/null 2>&1 || return 1
  done
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
  stamp_name=.complete-v10
  stamp="$root/$stamp_name"
  triple=$(dpkg-architecture -a"$arch" -qDEB_HOST_MULTIARCH 2>/dev/null)
  if [[ -f $stamp ]]; then
    if database_answers; then
      echo "fetch-target-libs: $root is complete"
      continue
    fi
    echo "fetch-target-libs: $root's package database does not name its libraries: making it again"
  fi
  # apt-get download of a foreign architecture needs it known to dpkg and its package lists.
  if ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
    $sudo dpkg --add-architecture "$arch"
    refresh_lists
  fi
  # libcamera-dev and cyclonedds-dev (the ROS 2 output's DDS) and everything they need at run
  # time (libcamera0.0.3, libudev1, gnutls, libddsc0debian, iceoryx, libssl3, ...).
  closure() {
    apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks \
      --no-replaces --no-enhances "libcamera-dev:$arch" "cyclonedds-dev:$arch" 2>/dev/null |
      sed -n "s/^\([a-z0-9][^ ]*\):$arch\$/\1/p" | sort -u
  }
  camera=$(closure || true)
  [[ $camera == *cyclonedds-dev* ]] || { refresh_lists; camera=$(closure || true); }
  [[ $camera == *libcamera-dev* && $camera == *cyclonedds-dev* ]] ||
    { echo "fetch-target-libs: no libcamera-dev:$arch or cyclonedds-dev:$arch in the package lists" >&2; exit 1; }
  work=$(mktemp -d)
  (
    cd "$work"
    listed=("${packages[@]}" "${recording[@]}" "${view[@]}" "${images[@]}" "${opencv[@]}" "${runtime[@]}")
    wanted=("${listed[@]/%/:$arch}" "${headers[@]}")
    for p in $camera; do
      [[ " ${listed[*]} " == *" $p "* ]] || wanted+=("$p:$arch")
    done
    if ! apt-get download -q "${wanted[@]}" >/dev/null 2>&1; then
      refresh_lists
      apt-get download -q "${wanted[@]}" >/dev/null
    fi
    rm -rf "$root.partial"
    db="$root.partial/dpkg"
    mkdir -p "$db/info" "$db/updates"
    echo 1 >"$db/info/format"  # multiarch names: info/<package>:<arch>.list
    : >"$db/status"
    for deb in ./*.deb; do
      package=$(dpkg-deb -f "$deb" Package)
      name=$package
      [[ $(dpkg-deb -f "$deb" Multi-Arch) == same ]] && name="$package:$arch"
      dpkg-deb -e "$deb" control
      for f in shlibs symbols; do
        if [[ -f control/$f ]]; then cp "control/$f" "$db/info/$name.$f"; fi
      done
      rm -rf control
      if [[ " ${runtime[*]} " == *" $package "* ]]; then
        # The cross toolchain's copy of each shared library of the package.
        dpkg-deb -c "$deb" | awk '{print $6}' |
          sed -n "s|^\./\(usr/\)\{0,1\}lib/$triple/\([^/]*\.so[.0-9]*\)\$|/usr/$triple/lib/\2|p" \
            >"$db/info/$name.list"
      else
        dpkg-deb -x "$deb" "$root.partial"
        # Where the files are here, so that the libraries found in this folder are the package's.
        dpkg-deb -c "$deb" | awk '$6 !~ /\/$/ {print $6}' | sed "s|^\.|$root|" >"$db/info/$name.list"
        dpkg-deb -f "$deb" Package Version Architecture | paste -sd' ' >>"$root.partial/$stamp_name"
      fi
      { dpkg-deb -f "$deb" | grep -v '^Status:'; echo "Status: install ok installed"; echo; } >>"$db/status"
    done
    # What update-alternatives makes when the packages are installed: libblas.so.3 and
    # liblapack.so.3 beside the other libraries, where the linker and the loader look.
    for lib in blas lapack; do
      ln -sf "$lib/lib$lib.so.3" "$root.partial/usr/lib/$triple/lib$lib.so.3"
    done
    # Links to absolute paths (zlib1g-dev's libz.so -> /lib/<triple>/libz.so.1.2.13) would name
    # the host's files: they are made relative, to the same file in this folder.
    find "$root.partial" -type l -lname '/*' | while read -r link; do
      ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$root.partial$(readlink "$link")")" "$link"
    done
  )
  rm -rf "$work" "$root"
  mv "$root.partial" "$root"
  if ! database_answers; then
    echo "fetch-target-libs: $root/dpkg does not name the libraries unpacked beside it" >&2
    exit 1
  fi
  echo "fetch-target-libs: $root ready"
done
