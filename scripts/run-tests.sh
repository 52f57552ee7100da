#!/usr/bin/env bash
# Every test: installs what is missing, fetches the data sets, builds the host, host-asan, host-tsan,
# aarch64 and armhf presets and runs all their tests (the cross-built ones under qemu-user),
# then builds the libFuzzer targets (fuzz preset) and runs each from its seed corpus. The cross
# presets also build the board's .deb and check its contents (scripts/check-package.sh). What the
# emulated boards boot (scripts/prepare-boards.sh) is made beside the host build, and the soak
# (5 minutes of the simulated board with faults) runs beside the presets after host. Then the
# virtual board's tests, and the deployment test installs the arm64 package on Debian booted with
# systemd (as root: debootstrap makes its root filesystem once). Last, it
# runs the main job (scripts/run-demo.sh) in a fresh copy of the tree with a fresh copy of the
# data sets and checks what it wrote (scripts/check-demo.sh): a broken main job fails the tests.
# This is the README's test command and what CI runs.
#
#   EPIPOLE_PRESETS="host aarch64"   run a subset of the presets
set -euo pipefail
cd "$(dirname "$0")/.."

presets=${EPIPOLE_PRESETS:-"host host-asan host-tsan aarch64 armhf fuzz"}
start=$SECONDS

./scripts/setup.sh
./scripts/fetch-data.sh
./scripts/check-format.sh
for preset in $presets; do
  case $preset in
    aarch64) ./scripts/fetch-target-libs.sh arm64 ;;
    armhf) ./scripts/fetch-target-libs.sh armhf ;;
  esac
done

# Background jobs run in their own sessions, so that stopping one stops what it started too (a
# QEMU guest, ctest's test programs); a failure of this script stops them all.
background=()
stop_background() {
  for pid in "${background[@]}"; do kill -- "-$pid" 2>/dev/null || true; done
}
trap stop_background EXIT
start_background() {  # LOG COMMAND...: the job's pid is in $!
  local log=$1
  shift
  setsid "$@" >"$log" 2>&1 </dev/null &
  background+=($!)
}

timings=""
with_boards=false
[[ " $presets " == *" host "* && " $presets " == *" aarch64 "* ]] && with_boards=true
if $with_boards; then
  # Downloads, a kernel module build and an emulated Debian install (alone about 7 minutes at
  # two thirds of the machine), made beside the host build rather than left to the last tiers.
  echo "=== boards: the emulated boards' kernels and root filesystem, made beside the host build"
  boards_log=$(mktemp)
  start_background "$boards_log" ./scripts/prepare-boards.sh
  boards_pid=$!
fi

for preset in $presets; do
  echo "=== $preset: configure and build"
  phase=$SECONDS
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset"
  built=$((SECONDS - phase))
  if [[ $preset == host && -n ${boards_pid:-} ]]; then
    # Its guest is not left running beside the tests, whose programs it would slow.
    echo "=== boards: waiting for scripts/prepare-boards.sh"
    boards_status=0
    wait "$boards_pid" || boards_status=$?
    cat "$boards_log"
    rm -f "$boards_log"
    if [[ $boards_status -ne 0 ]]; then
      echo "run-tests: scripts/prepare-boards.sh failed" >&2
      exit 1
    fi
    timings+="  boards: made beside the host build, waited for $((SECONDS - phase - built)) s more"$'\n'
    built=$((SECONDS - phase))
  fi
  echo "=== $preset: test"
  phase=$SECONDS
  # The virtual board (label vboard) boots the aarch64 build's firmware too, and the deployment
  # test (label deploy) installs its package: they run last.
  ctest --preset "$preset" --output-junit "junit-$preset.xml" -LE 'vboard|deploy|soak'
  case $preset in
    aarch64) ./scripts/check-package.sh build/aarch64 arm64 ;;
    armhf) ./scripts/check-package.sh build/armhf armhf ;;
  esac
  timings+="  $preset: built in $built s, tested in $((SECONDS - phase)) s"$'\n'
  if [[ $preset == host ]]; then
    # The soak (label soak, docs/testing.md): 5 minutes of the simulated board with faults (its
    # pool has two threads: alone it keeps both cores busy) beside the next presets' builds; its
    # result is waited for before the virtual board.
    echo "=== soak: 5 minutes of the simulated board with faults, in the background"
    soak_log=$(mktemp)
    start_background "$soak_log" env EPIPOLE_SOAK_SECONDS=300 ctest --preset host -L soak \
      --output-junit junit-soak.xml --output-on-failure -V
    soak_pid=$!
  fi
done

if [[ -n ${soak_pid:-} ]]; then
  echo "=== soak: its result"
  soak_status=0
  wait "$soak_pid" || soak_status=$?
  grep -E '^[0-9]+: soak:|tests passed|tests failed|Failure' "$soak_log" || true
  if [[ $soak_status -ne 0 ]]; then
    cat "$soak_log"
    rm -f "$soak_log"
    echo "run-tests: the soak failed" >&2
    exit 1
  fi
  rm -f "$soak_log"
  timings+="  soak: 300 s, beside the presets after host"$'\n'
fi

if $with_boards; then
  echo "=== vboard: the firmware on the virtual board (amd64 and arm64, docs/vboard.md)"
  phase=$SECONDS
  # No test is run twice: a failure that comes one run in four (a crash, a race) must show.
  ctest --preset host -L vboard --output-junit junit-vboard.xml --output-on-failure
  timings+="  vboard: tested in $((SECONDS - phase)) s"$'\n'
  echo "=== deploy: the arm64 package installed and run on Debian booted with systemd (docs/deploy.md)"
  phase=$SECONDS
  if [[ $(id -u) -eq 0 ]]; then
    ctest --preset host -L deploy --output-junit junit-deploy.xml --output-on-failure
    timings+="  deploy: tested in $((SECONDS - phase)) s"$'\n'
  else
    echo "deploy: NOT RUN: making its root filesystem (debootstrap) needs root; run as root to include it"
    timings+="  deploy: not run (needs root)"$'\n'
  fi
fi

if [[ " $presets " == *" host "* ]]; then
  # As a new user runs it: a copy of this tree without its build folders, the data sets without
  # what builds put there (the compiled cascade), so the main job must make all it needs itself.
  echo "=== demo: the main job (scripts/run-demo.sh) in a fresh copy of the tree, then a check of what it wrote"
  phase=$SECONDS
  demo=$(mktemp -d)
  trap 'rm -rf "$demo"; stop_background' EXIT
  mkdir "$demo/src" "$demo/data"
  git ls-files -z --cached --others --exclude-standard |
    while IFS= read -r -d '' f; do
      if [[ -e $f ]]; then printf '%s\0' "$f"; fi  # not a file deleted in the work tree
    done |
    cpio -pdm0 --quiet "$demo/src"
  data=${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}
  cp -r "$data/." "$demo/data/"
  rm -rf "$demo/data/compiled"
  EPIPOLE_DATA_DIR="$demo/data" "$demo/src/scripts/run-demo.sh" "$demo/out"
  ./scripts/check-demo.sh "$demo/out"
  timings+="  demo: ran and checked in $((SECONDS - phase)) s"$'\n'
fi

printf "%s" "$timings"

echo "run-tests: all presets passed ($presets) in $((SECONDS - start)) s"
