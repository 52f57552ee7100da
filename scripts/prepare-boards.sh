#!/usr/bin/env bash
# Everything the emulated boards boot that does not come from a build, made once into the cache:
# the virtual board's kernels and modules for amd64 and arm64 (docs/vboard.md) and, as root, the
# deployment test's root filesystem (docs/deploy.md). Each step returns at once when its result
# is cached. run-tests.sh runs this beside the builds, so that the last tiers find it ready.
#
#   scripts/prepare-boards.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
start=$SECONDS

for arch in amd64 arm64; do
  "$here/vboard/fetch-kernel.sh" "$arch"
  "$here/vboard/build-modules.sh" "$arch"
done
if [[ $(id -u) -eq 0 ]]; then
  "$here/deploy/make-rootfs.sh"
else
  echo "prepare-boards: the deployment test's root filesystem is not made: debootstrap needs root"
fi
echo "prepare-boards: ready in $((SECONDS - start)) s"
