#!/usr/bin/env bash
# ARM instruction counts without a board: a cross build's epipole-bench under qemu-user with the
# project's instruction-counting plugin (tests/arm_counts/insn_count_plugin), each side alone (Epipole's
# stages with their NEON kernels; Debian's OpenCV for the same ISA doing the same work), one
# thread, on the simulated board's Aloe pair (or the scene a row names), for the rows of
# tests/arm_counts/rows (each stage alone, with some keys of the board set, and the whole
# pipeline). Per pair: the count of 2N
# pairs minus that of N (the set-up cancels out), divided by N. Counts do not depend on the
# machine's load. The detection rows need the compiled cascades the host build writes into the
# data cache; without them those rows are left out, with the reason.
#
#   scripts/arm-bench.sh OUT_DIR [PRESET]   writes OUT_DIR/arm-bench.json (PRESET: aarch64, the
#                                           default, or armhf)
#   EPIPOLE_ARM_PAIRS=N                     N (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/arm-bench.sh OUT_DIR [aarch64|armhf]}
preset=${2:-aarch64}
case $preset in
  aarch64) arch=arm64 ;;
  armhf) arch=armhf ;;
  *) echo "arm-bench: $preset is not a cross preset (aarch64, armhf)" >&2; exit 2 ;;
esac
pairs=${EPIPOLE_ARM_PAIRS:-2}
[[ $pairs =~ ^[1-9][0-9]*$ ]] || { echo "arm-bench: EPIPOLE_ARM_PAIRS=$pairs is not a count" >&2; exit 2; }
build=build/$preset
mkdir -p "$out"

./scripts/fetch-target-libs.sh "$arch"
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" --target epipole-bench epipole_insn_count

plugin=$build/tests/arm_counts/insn_count_plugin/libepipole_insn_count.so
bench=$build/host-tools/bench/epipole-bench
count_file=$(mktemp)
trap 'rm -f "$count_file"' EXIT

# count NAME N SIDE STAGES [KEY=VALUE|scene=NAME|--OPTION=VALUE...]: the guest instructions of a whole run of N pairs of
# one side.
count() {
  local name=$1 n=$2 side=--no-opencv stages=$4
  [[ $3 == opencv ]] && side=--opencv-only
  local args=() scene=aloe
  [[ $stages != all ]] && args+=(--stages "$stages")
  for setting in "${@:5}"; do
    if [[ $setting == scene=* ]]; then
      scene=${setting#scene=}
    elif [[ $setting == --* ]]; then
      args+=("$setting")
    else
      args+=(--set "$setting")
    fi
  done
  "$build/run-on-target" -plugin "$plugin,out=$count_file" "$bench" --board board/sim \
    --scene "$scene" --threads 1 --warmup 0 -n "$n" "$side" "${args[@]}" --json \
    >"$out/bench-$name-$3-$n.json"
  cat "$count_file"
}

rows=()
while read -r name stages settings; do
  [[ -z $name || $name == \#* ]] && continue
  rows+=("$name $stages $settings")
done <tests/arm_counts/rows

json=""
for row in "${rows[@]}"; do
  read -r name stages settings <<<"$row"
  read -r -a sets <<<"$settings"
  declare -A per_pair=()
  for side in epipole opencv; do
    once=$(count "$name" "$pairs" "$side" "$stages" "${sets[@]}")
    twice=$(count "$name" $((2 * pairs)) "$side" "$stages" "${sets[@]}")
    per_pair[$side]=$(((twice - once) / pairs))
    echo "arm-bench: $name, $side: $once instructions for $pairs pairs, $twice for" \
      "$((2 * pairs)): ${per_pair[$side]} a pair"
  done
  notes=$(jq -r '.notes | join("; ")' "$out/bench-$name-epipole-$pairs.json")
  if [[ $notes == *"detect: off"* || $notes == *"opencv detect: off"* ]]; then
    echo "arm-bench: $name left out: $notes" >&2
    continue
  fi
  size=$(jq -r '"\(.width)x\(.height)"' "$out/bench-$name-epipole-$pairs.json")
  json+="${json:+, }{\"name\": \"$name\", \"size\": \"$size\", \"ours\": ${per_pair[epipole]}, \"opencv\": ${per_pair[opencv]}}"
done
echo "{\"preset\": \"$preset\", \"stages\": [$json]}" | jq . >"$out/arm-bench.json"
echo "arm-bench: $out/arm-bench.json"
