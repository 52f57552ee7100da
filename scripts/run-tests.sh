#!/usr/bin/env bash
# Every test: installs what is missing, fetches the data sets, builds the host, host-asan, host-tsan,
# aarch64 and armhf presets and runs all their tests (the cross-built ones under qemu-user),
# then builds the libFuzzer targets (fuzz preset) and runs each from its seed corpus. The cross
# presets also build the board's .deb and check its contents (scripts/check-package.sh). What the
# emulated boards boot (scripts/prepare-boards.sh) is made beside the host build. Then the
# virtual board's tests, and the deployment test installs the arm64 package on Debian booted with
# systemd (as root: debootstrap makes its root filesystem once); the soak (5 minutes of the
# simulated board with faults) runs beside those two at idle priority, in the time their
# emulated boards leave the cores waiting (without the boards: beside the presets after host). Last, it
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
# PID LOG WHAT [PATTERN]: waits for a background job; shows its log (only the lines matching
# PATTERN when given and the job passed) and stops here when it failed. log_end: when the log
# was last written (seconds since the epoch), about when the job ended.
wait_background() {
  local pid=$1 log=$2 what=$3 pattern=${4:-} status=0
  wait "$pid" || status=$?
  log_end=$(stat -c %Y "$log")
  if [[ $status -ne 0 || -z $pattern ]]; then
    cat "$log"
  else
    grep -E "$pattern" "$log" || true
  fi
  rm -f "$log"
  if [[ $status -ne 0 ]]; then
    echo "run-tests: $what failed" >&2
    exit 1
  fi
}
# The soak (label soak, docs/testing.md): 5 minutes of the simulated board with faults, its pool
# two threads. PRIORITY: chrt's arguments, e.g. --idle 0 (only when nothing else wants a core).
start_soak() {
  soak_log=$(mktemp)
  start_background "$soak_log" chrt "$@" env EPIPOLE_SOAK_SECONDS=300 ctest --preset host -L soak \
    --output-junit junit-soak.xml --output-on-failure -V
  soak_pid=$!
  soak_start=$(date +%s)
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
    wait_background "$boards_pid" "$boards_log" scripts/prepare-boards.sh
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
  if [[ $preset == host ]] && ! $with_boards; then
    # Alone the soak keeps both cores busy: here it shares them with the next presets.
    echo "=== soak: 5 minutes of the simulated board with faults, in the background"
    start_soak --other 0
    soak_beside="the presets after host"
  fi
done

if $with_boards; then
  # The emulated boards leave about two fifths of the cores idle in their 5 minutes (their
  # guests' boots, the deployment test's pauses): the soak runs in that time, and as a SCHED_IDLE
  # job takes no core from them (they still share the caches and the memory).
  echo "=== soak: 5 minutes of the simulated board with faults, in the background at idle priority"
  start_soak --idle 0
  soak_beside="the virtual board, at idle priority"
  [[ $(id -u) -eq 0 ]] && soak_beside="the virtual board and the deployment test, at idle priority"
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

if [[ -n ${soak_pid:-} ]]; then
  echo "=== soak: its result"
  wait_background "$soak_pid" "$soak_log" "the soak" '^[0-9]+: soak:|tests passed|tests failed|Failure'
  timings+="  soak: 300 s beside $soak_beside, done $((log_end - soak_start)) s after its start"$'\n'
fi

printf "%s" "$timings"

echo "run-tests: all presets passed ($presets) in $((SECONDS - start)) s"
