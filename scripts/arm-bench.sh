#!/usr/bin/env bash
# ARM instruction counts without a board: the aarch64 build's epipole-bench under qemu-aarch64
# with the project's instruction-counting plugin (host-tools/qemu_insn_count), each side alone
# (Epipole's pipeline with its NEON kernels; Debian's arm64 OpenCV doing the same work), one
# thread, on the simulated board's Aloe pair. Per pair: the count of 2N pairs minus that of N
# (the set-up cancels out), divided by N. Counts are exact: the machine's load does not enter.
#
#   scripts/arm-bench.sh OUT_DIR      writes OUT_DIR/arm-bench.json
#   EPIPOLE_ARM_PAIRS=N               N (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/arm-bench.sh OUT_DIR}
pairs=${EPIPOLE_ARM_PAIRS:-2}
[[ $pairs =~ ^[1-9][0-9]*$ ]] || { echo "arm-bench: EPIPOLE_ARM_PAIRS=$pairs is not a count" >&2; exit 2; }
build=build/aarch64
mkdir -p "$out"

./scripts/fetch-target-libs.sh arm64
cmake --preset aarch64 >/dev/null
cmake --build --preset aarch64 --target epipole-bench epipole_insn_count

plugin=$build/host-tools/qemu_insn_count/libepipole_insn_count.so
bench=$build/host-tools/bench/epipole-bench
count_file=$(mktemp)
trap 'rm -f "$count_file"' EXIT

# count N SIDE: the guest instructions of a whole run of N pairs of one side.
count() {
  local side=--no-opencv
  [[ $2 == opencv ]] && side=--opencv-only
  "$build/run-on-target" -plugin "$plugin,out=$count_file" "$bench" --board board/sim \
    --scene aloe --threads 1 --warmup 0 -n "$1" "$side" --json >"$out/bench-$2-$1.json"
  cat "$count_file"
}

declare -A per_pair
for side in epipole opencv; do
  once=$(count "$pairs" "$side")
  twice=$(count $((2 * pairs)) "$side")
  per_pair[$side]=$(((twice - once) / pairs))
  echo "arm-bench: $side: $once instructions for $pairs pairs, $twice for $((2 * pairs)):" \
    "${per_pair[$side]} a pair"
done

size=$(python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print("%dx%d" % (j["width"], j["height"]))' \
  "$out/bench-epipole-$pairs.json")
cat >"$out/arm-bench.json" <<JSON
{"stages": [{"name": "pipeline", "size": "$size", "ours": ${per_pair[epipole]}, "opencv": ${per_pair[opencv]}}]}
JSON
echo "arm-bench: $out/arm-bench.json"
