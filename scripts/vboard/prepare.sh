#!/usr/bin/env bash
# Everything a boot of the virtual board needs, each step skipped when its result is in the
# cache: the kernel and the out-of-tree modules; then the initramfs with the firmware of
# BUILD_DIR, made every time, at OUTPUT (by default in the kernel's cache folder, one per build
# folder).
#
#   scripts/vboard/prepare.sh amd64|arm64 BUILD_DIR [OUTPUT]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
arch=${1:?usage: prepare.sh amd64|arm64 BUILD_DIR [OUTPUT]}
build=$(cd "${2:?usage: prepare.sh amd64|arm64 BUILD_DIR [OUTPUT]}" && pwd)
vboard_check_arch "$arch"

start=$SECONDS
# Resolved once (apt-cache takes seconds), for every step.
EPIPOLE_VBOARD_KVER=$(vboard_kernel_version "$arch")
export EPIPOLE_VBOARD_KVER
"$here/fetch-kernel.sh" "$arch"
"$here/build-modules.sh" "$arch"
# The initramfs belongs to the build it holds: written where the caller says (the tests: into
# the build tree), else beside the kernel, named by the build folder.
initramfs=${3:-"$(vboard_cache "$EPIPOLE_VBOARD_KVER")/initramfs-$(echo -n "$build" | md5sum | cut -c1-12).cpio"}
rm -f "$initramfs"  # a link to the cache, as earlier versions made it
"$here/make-initramfs.sh" "$arch" "$build" "$initramfs"
echo "prepare: $arch ready in $((SECONDS - start)) s"
