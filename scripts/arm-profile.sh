#!/usr/bin/env bash
# Where one pair's ARM instructions go, function by function: the aarch64 (or armhf) build's
# epipole-bench under qemu-user with the project's counting plugin and its profile
# (tests/arm_counts/insn_count_plugin), Epipole's side alone, one thread, on the simulated board's Aloe
# pair, for N and 2N pairs; each function's count for 2N minus that for N, divided by N, largest
# first, demangled. The place to start a NEON tuning (docs/performance.md).
#
#   scripts/arm-profile.sh [--preset armhf] [--top K] [BENCH OPTIONS...]
#       e.g. scripts/arm-profile.sh --stages disparity
#            scripts/arm-profile.sh --stages detect --set 'detector.cascade=...'
#   EPIPOLE_ARM_PAIRS=N      N (default 1)
set -euo pipefail
cd "$(dirname "$0")/.."
preset=aarch64
top=25
while (($#)); do
  case $1 in
    --preset) preset=${2:?--preset needs aarch64 or armhf}; shift 2 ;;
    --top) top=${2:?--top needs a count}; shift 2 ;;
    *) break ;;
  esac
done
case $preset in
  aarch64 | armhf) ;;
  *) echo "arm-profile: $preset is not a cross preset (aarch64, armhf)" >&2; exit 2 ;;
esac
[[ $top =~ ^[1-9][0-9]*$ ]] || { echo "arm-profile: --top $top is not a count" >&2; exit 2; }
pairs=${EPIPOLE_ARM_PAIRS:-1}
[[ $pairs =~ ^[1-9][0-9]*$ ]] || { echo "arm-profile: EPIPOLE_ARM_PAIRS=$pairs is not a count" >&2; exit 2; }
build=build/$preset
if [[ ! -x $build/run-on-target ]]; then
  echo "arm-profile: no $build: build it first (cmake --preset $preset && cmake --build --preset $preset)" >&2
  exit 1
fi
cmake --build --preset "$preset" --target epipole-bench epipole_insn_count >/dev/null

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for n in "$pairs" $((2 * pairs)); do
  "$build/run-on-target" \
    -plugin "$build/tests/arm_counts/insn_count_plugin/libepipole_insn_count.so,out=$work/count-$n,profile=$work/profile-$n" \
    "$build/host-tools/bench/epipole-bench" --board board/sim --scene aloe --threads 1 --warmup 0 \
    --no-opencv -n "$n" "$@" --json >"$work/bench-$n.json"
done
once=$(<"$work/count-$pairs")
twice=$(<"$work/count-$((2 * pairs))")
echo "guest instructions a pair: $(((twice - once) / pairs)) ($preset, epipole-bench $*)"
# COUNT SYMBOL lines of both runs: the difference per symbol, a pair's share.
awk -v pairs="$pairs" -v total=$(((twice - once) / pairs)) '
  FNR == NR { once[$2] = $1; next }
  { per_pair = ($1 - once[$2]) / pairs; if (per_pair > 0) printf "%14d %5.1f%% %s\n", per_pair, 100 * per_pair / total, $2 }
' "$work/profile-$pairs" "$work/profile-$((2 * pairs))" | sort -rn | head -n "$top" | c++filt
