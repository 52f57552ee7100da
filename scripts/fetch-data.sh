#!/usr/bin/env bash
# Fetches the real data sets (design brief §4) from Debian's opencv-doc and opencv-data packages
# into a cache folder, without installing anything. Idempotent: a complete cache is left as is.
#
#   EPIPOLE_DATA_DIR   where the data goes (default: ${XDG_CACHE_HOME:-~/.cache}/epipole/data)
#
# Layout of the cache:
#   samples/    OpenCV's example data: left01..14.jpg, right01..14.jpg, aloeL/R.jpg, aloeGT.png,
#               graf1.png, graf3.png, H1to3p.xml, messi5.jpg, ...
#   cascades/   haarcascades/*.xml and lbpcascades/*.xml
set -euo pipefail

data_dir=${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}
stamp="$data_dir/.complete-v1"
if [[ -f $stamp ]]; then
  echo "fetch-data: $data_dir is complete"
  exit 0
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

download() {
  # apt-get download needs current package lists; refresh them once if it fails.
  if ! apt-get download -q "$@" >/dev/null 2>&1; then
    sudo=""
    if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
    $sudo apt-get update -qq
    apt-get download -q "$@" >/dev/null
  fi
}
echo "fetch-data: downloading opencv-doc and opencv-data"
download opencv-doc opencv-data

samples=./usr/share/doc/opencv-doc/examples/data/
mkdir -p extract
dpkg-deb --fsys-tarfile opencv-doc_*.deb | tar -x -C extract "$samples"
dpkg-deb --fsys-tarfile opencv-data_*.deb | tar -x -C extract ./usr/share/opencv4/
# Debian compresses some documentation files; the data sets are wanted as they were.
find "extract/$samples" -name '*.gz' -exec gunzip -f {} +

rm -rf "$data_dir.partial"
mkdir -p "$data_dir.partial/cascades"
mv "extract/$samples" "$data_dir.partial/samples"
mv extract/usr/share/opencv4/haarcascades extract/usr/share/opencv4/lbpcascades \
  "$data_dir.partial/cascades/"

for f in samples/left01.jpg samples/right14.jpg samples/aloeL.jpg samples/aloeR.jpg \
  samples/aloeGT.png samples/graf1.png samples/graf3.png samples/H1to3p.xml samples/messi5.jpg \
  cascades/haarcascades/haarcascade_frontalface_default.xml \
  cascades/lbpcascades/lbpcascade_frontalface_improved.xml; do
  if [[ ! -s "$data_dir.partial/$f" ]]; then
    echo "fetch-data: $f is missing from the packages" >&2
    exit 1
  fi
done

dpkg-deb -f opencv-doc_*.deb Package Version >"$data_dir.partial/.complete-v1"
dpkg-deb -f opencv-data_*.deb Package Version >>"$data_dir.partial/.complete-v1"
rm -rf "$data_dir"
mv "$data_dir.partial" "$data_dir"
echo "fetch-data: $data_dir ready ($(du -sh "$data_dir" | cut -f1))"
