# Shared by the deployment test's scripts (sourced after scripts/vboard/common.sh).
#
#   EPIPOLE_DEPLOY_CACHE   parent folder (default: ${XDG_CACHE_HOME:-~/.cache}/epipole/deploy)

deploy_cache() {
  echo "${EPIPOLE_DEPLOY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/deploy}"
}

# The root filesystem of a kernel version: a new kernel (a security update) is a new image.
deploy_rootfs_dir() {
  echo "$(deploy_cache)/bookworm-arm64-$1"
}

# The .ko files the named modules need, dependencies first (kmod reads the unpacked kernel);
# built-in ones need none.
deploy_module_closure() {
  local image=$1 kver=$2 module
  shift 2
  for module in "$@"; do
    modprobe -d "$image" -S "$kver" --show-depends "$module" | awk '$1 == "insmod" {print $2}'
  done | awk '!seen[$0]++'
}
