#!/usr/bin/env bash
# Installs every build and test dependency of Epipole from Debian's packages, and the npm
# packages of the test clients (tests/clients, pinned by its package-lock.json).
# Idempotent: packages already present are not fetched again. Run as root (or with sudo).
set -euo pipefail

packages=(
  # build tools
  build-essential cmake ninja-build pkg-config git clang-format ccache
  # host libraries
  libsimde-dev libeigen3-dev libyaml-cpp-dev libgpiod-dev libcamera-dev libpng-dev libjpeg-dev
  libzstd-dev zlib1g-dev cyclonedds-dev cyclonedds-tools libcivetweb-dev
  libturbojpeg0-dev
  libcli11-dev nlohmann-json3-dev libpugixml-dev
  libavformat-dev libavcodec-dev libswscale-dev libavutil-dev
  # tests, benchmarks and host-only references (never linked into the firmware)
  googletest libgtest-dev libgmock-dev libbenchmark-dev libopencv-dev
  # another DDS vendor's subscriber for the ROS 2 output's tests (Fast DDS, ROS 2's default)
  libfastrtps-dev
  # a browser for the live view's page test (headless)
  chromium
  # clang with its sanitizer and libFuzzer runtimes (the fuzz preset)
  clang libclang-rt-14-dev
  # cross compilers and the user-mode emulator that runs cross-built tests
  g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user
  # the virtual board (docs/vboard.md): whole-system emulators, module tools, initramfs packing
  qemu-system-x86 qemu-system-arm kmod cpio xz-utils
  # the deployment test (docs/deploy.md): a Debian root filesystem, its disk image and overlays
  debootstrap qemu-utils e2fsprogs
  # data fetching (apt-get download + dpkg-deb), the package's dependencies (dpkg-shlibdeps)
  dpkg dpkg-dev ca-certificates
  # checking what the main job wrote (scripts/check-demo.sh) and the board package (lintian,
  # systemd-analyze for the unit's sandbox)
  jq lintian systemd
  # the programs' manual pages, made from their --help
  help2man
)

# The independent clients the tests check the outputs with run on Node.js: Debian's, unless the
# machine has one already (a newer one from elsewhere is kept).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

# The test clients' npm packages, as the lock file pins them (again only when it changed).
install_clients() {
  local clients
  clients="$(dirname "$0")/../tests/clients"
  if [[ ! -f $clients/node_modules/.package-lock.json ||
    $clients/package-lock.json -nt $clients/node_modules/.package-lock.json ]]; then
    echo "setup: installing the test clients' npm packages"
    (cd "$clients" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages present"
  install_clients
  exit 0
fi

sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
install_clients
