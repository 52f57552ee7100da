#!/usr/bin/env bash
# Everything one run of the deployment test needs (docs/deploy.md), in OUTPUT_DIR:
#   disk.qcow2    a copy-on-write overlay of the cached root filesystem (make-rootfs.sh)
#   payload.img   the test's disk: the board package of BUILD_DIR as built, and the same package
#                 as two newer versions (the upgrades), a local apt repository with the
#                 dependencies apt would fetch for it on that root filesystem, the board file
#                 and the script the guest runs (tests/deploy/guest/)
#
#   scripts/deploy/prepare.sh BUILD_DIR OUTPUT_DIR
#
# BUILD_DIR is an aarch64 build whose package is made (scripts/check-package.sh makes it;
# otherwise `cpack -G DEB` in it). The dependencies are downloaded once into the cache.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/../vboard/common.sh"
source "$here/common.sh"
usage="usage: prepare.sh BUILD_DIR OUTPUT_DIR"
build=$(cd "${1:?$usage}" && pwd)
output=${2:?$usage}
guest="$here/../../tests/deploy/guest"
start=$SECONDS

deb=$(ls "$build"/epipole_*_arm64.deb 2>/dev/null | head -1)
[[ -n $deb ]] || {
  echo "prepare: no epipole_*_arm64.deb in $build (scripts/check-package.sh $build arm64 makes it)" >&2
  exit 1
}
"$here/make-rootfs.sh"
rootfs=$(deploy_rootfs_dir "$(vboard_kernel_version arm64)")

rm -rf "$output"
mkdir -p "$output/payload/repo"
payload="$output/payload"
version=$(dpkg-deb -f "$deb" Version)
cp "$deb" "$payload/"
# The upgrades: the same files under newer versions, as a new release would come.
unpacked=$(mktemp -d)
trap 'rm -rf "$unpacked"' EXIT
dpkg-deb -R "$deb" "$unpacked/package"
for n in 1 2; do
  sed -i "s/^Version: .*/Version: $version+upgrade$n/" "$unpacked/package/DEBIAN/control"
  dpkg-deb --root-owner-group -b "$unpacked/package" "$payload/epipole_${version}+upgrade${n}_arm64.deb" >/dev/null
done

# The dependencies: what apt itself would install for the package on the root filesystem (its
# dpkg database, read out of the image), downloaded once into the cache.
debugfs -R 'cat /var/lib/dpkg/status' "$rootfs/rootfs.img" 2>/dev/null >"$unpacked/status"
[[ -s $unpacked/status ]] || {
  echo "prepare: cannot read the dpkg database of $rootfs/rootfs.img" >&2
  exit 1
}
wanted=$(apt-get -s -q -o Dir::State::status="$unpacked/status" -o APT::Architecture=arm64 \
  -o APT::Architectures::=arm64 install "$deb" 2>&1 |
  awk '$1 == "Inst" && $2 != "epipole" {gsub(/[()]/, "", $3); print $2 ":arm64=" $3}') || true
debs=$(deploy_cache)/debs
mkdir -p "$debs"
# A downloaded file's name has the version's epoch as %3a (libjpeg62-turbo_1%3a2.1.5-2_arm64.deb).
downloaded() { ls "$debs/${name}_${package_version/:/%3a}_"*.deb 2>/dev/null | head -1 || true; }
for package in $wanted; do
  name=${package%%:*} package_version=${package#*=}
  file=$(downloaded)
  if [[ -z $file ]]; then
    (cd "$debs" && vboard_download "$package")
    file=$(downloaded)
    [[ -n $file ]] || { echo "prepare: $package was not downloaded into $debs" >&2; exit 1; }
  fi
  cp "$file" "$payload/repo/"
done
(cd "$payload/repo" && dpkg-scanpackages -m . 2>/dev/null >Packages)
echo "prepare: $(echo "$wanted" | wc -w) dependencies in the local repository"

install -m 0755 "$guest/run.sh" "$payload/run.sh"
# The virtual board's trigger driver (tests/vboard/guest), built beside the package: it makes the
# gpio-sim line's edges follow the left camera's frames, as on the virtual board.
[[ -x $build/tests/vboard/vboard-trigger ]] || {
  echo "prepare: no tests/vboard/vboard-trigger in $build" >&2
  exit 1
}
install -m 0755 "$build/tests/vboard/vboard-trigger" "$payload/"
install -m 0644 "$guest/board.yaml" "$guest/udev.rules" "$payload/"
size=$(du -sm "$payload" | cut -f1)
mke2fs -q -t ext4 -L epipole-test -d "$payload" "$output/payload.img" "$((size + 32))M"
qemu-img create -q -f qcow2 -b "$rootfs/rootfs.img" -F raw "$output/disk.qcow2"
ln -sfn "$rootfs" "$output/rootfs"
echo "prepare: $output ready in $((SECONDS - start)) s"
