#!/usr/bin/env bash
# ARM instruction counts without a board: the aarch64 build's epipole-bench under qemu-aarch64
# with the project's instruction-counting plugin (host-tools/qemu_insn_count), each side alone
# (Epipole's stages with their NEON kernels; Debian's arm64 OpenCV doing the same work), one
# thread, on the simulated board's Aloe pair, for each stage alone and for the whole pipeline.
# Per pair: the count of 2N pairs minus that of N (the set-up cancels out), divided by N. Counts
# do not depend on the machine's load. The detection row needs the compiled cascade the host
# build writes into the data cache; without it that row is left out, with the reason.
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

# count N SIDE STAGES: the guest instructions of a whole run of N pairs of one side.
count() {
  local side=--no-opencv
  [[ $2 == opencv ]] && side=--opencv-only
  local stages=()
  [[ $3 != all ]] && stages=(--stages "$3")
  "$build/run-on-target" -plugin "$plugin,out=$count_file" "$bench" --board board/sim \
    --scene aloe --threads 1 --warmup 0 -n "$1" "$side" "${stages[@]}" --json \
    >"$out/bench-$3-$2-$1.json"
  cat "$count_file"
}

# The rows: a name and the simulated board's stages it runs (its corners are FAST, its
# disparity SGM with 128 disparities, its detector OpenCV's Haar face cascade).
rows=("remap rectify" "fast corners" "sgm disparity" "haar detect" "pipeline all")
json=""
for row in "${rows[@]}"; do
  read -r name stages <<<"$row"
  declare -A per_pair=()
  for side in epipole opencv; do
    once=$(count "$pairs" "$side" "$stages")
    twice=$(count $((2 * pairs)) "$side" "$stages")
    per_pair[$side]=$(((twice - once) / pairs))
    echo "arm-bench: $name, $side: $once instructions for $pairs pairs, $twice for" \
      "$((2 * pairs)): ${per_pair[$side]} a pair"
  done
  notes=$(python3 -c 'import json,sys; print("; ".join(json.load(open(sys.argv[1]))["notes"]))' \
    "$out/bench-$stages-epipole-$pairs.json")
  if [[ $notes == *"detect: off"* || $notes == *"opencv detect: off"* ]]; then
    echo "arm-bench: $name left out: $notes" >&2
    continue
  fi
  size=$(python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print("%dx%d" % (j["width"], j["height"]))' \
    "$out/bench-$stages-epipole-$pairs.json")
  json+="${json:+, }{\"name\": \"$name\", \"size\": \"$size\", \"ours\": ${per_pair[epipole]}, \"opencv\": ${per_pair[opencv]}}"
done
echo "{\"stages\": [$json]}" >"$out/arm-bench.json"
echo "arm-bench: $out/arm-bench.json"
