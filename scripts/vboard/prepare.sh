#!/usr/bin/env bash
# Everything a boot of the virtual board needs, each step skipped when its result is in the
# cache: the kernel, the out-of-tree modules, and an initramfs with the firmware of BUILD_DIR
# (in the kernel's cache folder, one per build folder). LINK, when given, becomes a symbolic link
# to that initramfs.
#
#   scripts/vboard/prepare.sh amd64|arm64 BUILD_DIR [LINK]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
arch=${1:?usage: prepare.sh amd64|arm64 BUILD_DIR [LINK]}
build=$(cd "${2:?usage: prepare.sh amd64|arm64 BUILD_DIR [LINK]}" && pwd)
vboard_check_arch "$arch"

start=$SECONDS
# Resolved once (apt-cache takes seconds), for every step.
EPIPOLE_VBOARD_KVER=$(vboard_kernel_version "$arch")
export EPIPOLE_VBOARD_KVER
"$here/fetch-kernel.sh" "$arch"
"$here/build-modules.sh" "$arch"
initramfs="$(vboard_cache "$EPIPOLE_VBOARD_KVER")/initramfs-$(echo -n "$build" | md5sum | cut -c1-12).cpio"
"$here/make-initramfs.sh" "$arch" "$build" "$initramfs"
if [[ -n ${3:-} ]]; then ln -sfn "$initramfs" "$3"; fi
echo "prepare: $arch ready in $((SECONDS - start)) s"
