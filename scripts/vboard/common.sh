# Shared by the virtual board's scripts (sourced, not run): the guest architecture, the kernel
# version Debian ships for it today, and the cache folder keyed by that version.
#
#   EPIPOLE_VBOARD_CACHE   parent folder (default: ${XDG_CACHE_HOME:-~/.cache}/epipole/vboard)
#   EPIPOLE_VBOARD_KVER    the kernel to use (default: what linux-image-ARCH depends on)

vboard_check_arch() {
  case $1 in
    amd64 | arm64) ;;
    *)
      echo "vboard: unknown architecture '$1' (expected amd64 or arm64)" >&2
      exit 2
      ;;
  esac
}

# The kernel's ABI name (6.1.0-NN-ARCH) is what Debian's meta package depends on today: it moves
# with every security update, so it is never written down anywhere.
vboard_kernel_version() {
  local arch=$1 qualifier="" package
  if [[ -n ${EPIPOLE_VBOARD_KVER:-} ]]; then
    echo "$EPIPOLE_VBOARD_KVER"
    return
  fi
  [[ $arch == "$(dpkg --print-architecture)" ]] || qualifier=":$arch"
  package=$(apt-cache depends "linux-image-$arch$qualifier" 2>/dev/null |
    awk '/Depends: linux-image-/ {print $2; exit}')
  package=${package%%:*}
  if [[ -z $package ]]; then
    echo "vboard: apt-cache knows no linux-image-$arch$qualifier (apt-get update?)" >&2
    exit 1
  fi
  echo "${package#linux-image-}"
}

# The Debian version of a binary package (6.1.192-3): the headers, kbuild and source packages of
# a kernel must all be that one.
vboard_package_version() {
  apt-cache policy "$1" | awk '/Candidate:/ {print $2; exit}'
}

vboard_cache() {
  echo "${EPIPOLE_VBOARD_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/vboard}/$1"
}

# apt-get download into the current folder; the package lists are refreshed once if they are
# out of date (the registry keeps only the newest kernel).
vboard_download() {
  if ! apt-get download -q "$@" >/dev/null 2>&1; then
    local sudo=""
    [[ $(id -u) -eq 0 ]] || sudo="sudo"
    # Both architectures may get here at once: apt-get update refuses to share its lists' lock.
    mkdir -p "$(vboard_cache "")"
    (
      flock 9
      $sudo apt-get update -qq
    ) 9>"$(vboard_cache apt-update.lock)"
    apt-get download -q "$@" >/dev/null
  fi
}

vboard_cross_prefix() {
  [[ $1 == "$(dpkg --print-architecture)" ]] || echo "aarch64-linux-gnu-"
}
