#!/usr/bin/env bash
# Cycle estimates for the boards' ARM cores, from the code as compiled (docs/performance.md, "ARM
# cycle estimates"). For each row of tests/arm_counts/rows, the aarch64 build's epipole-bench runs
# under qemu-user with the project's counting plugin, which finds the translated blocks a pair
# executes and how often (blocks=FILE: 1 and 2 pairs, the difference). The hottest blocks, those
# making up 90 % of a pair's instructions (the inner loops), are disassembled from the binary and
# run through llvm-mca with LLVM's scheduling model of each core: cycles per execution, times
# executions. The remaining instructions are taken at the covered blocks' instructions per cycle.
# These are estimates: llvm-mca assumes every load hits the L1 cache and every branch is
# predicted, and models a block as if it looped on itself.
#
#   scripts/arm-mca.sh OUT_DIR   writes OUT_DIR/arm-mca.json, OUT_DIR/blocks-ROW.txt (each hot
#                                block: instructions a pair, executions, cycles an execution on
#                                each model, symbol) and prints a table
#   EPIPOLE_ARM_ROWS="remap bm"  only those rows
#
# Models: LLVM 19's (Debian's llvm-19): `neoverse-n1` for the Cortex-A76 of a Pi 5 (the Neoverse
# N1 is the A76's server sibling, and LLVM's A76 has no model of its own), `cortex-a72` for a Pi 4
# (LLVM models it with its Cortex-A57).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/arm-mca.sh OUT_DIR}
mca=$(command -v llvm-mca-19 || true)
if [[ -z $mca ]]; then
  echo "arm-mca: llvm-mca-19 is missing: apt-get install llvm-19" >&2
  exit 1
fi
preset=aarch64
build=build/$preset
mkdir -p "$out"
./scripts/fetch-target-libs.sh arm64
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" --target epipole-bench epipole_insn_count >/dev/null

plugin=$build/tests/arm_counts/insn_count_plugin/libepipole_insn_count.so
bench=$build/host-tools/bench/epipole-bench
objdump=aarch64-linux-gnu-objdump
nm=aarch64-linux-gnu-nm
models=(neoverse-n1 cortex-a72)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The binary's functions: "ADDRESS SIZE NAME" (decimal), for placing the blocks QEMU reported.
"$nm" --defined-only --print-size --radix=d "$bench" | awk 'NF == 4 { print $1 + 0, $2 + 0, $4 }' \
  >"$work/symbols"

# run N STAGES [KEY=VALUE...]: N pairs under the plugin; the count and blocks files in $work.
run() {
  local n=$1 stages=$2
  local args=()
  [[ $stages != all ]] && args+=(--stages "$stages")
  for setting in "${@:3}"; do args+=(--set "$setting"); done
  "$build/run-on-target" -plugin "$plugin,out=$work/count-$n,blocks=$work/blocks-$n" "$bench" \
    --board board/sim --scene aloe --threads 1 --warmup 0 -n "$n" --no-opencv "${args[@]}" \
    --json >"$work/bench-$n.json"
}

# mca_cycles FILE MODEL: llvm-mca's cycles for one execution of the block in FILE (empty when
# llvm-mca cannot read it).
mca_cycles() {
  "$mca" -mtriple=aarch64-linux-gnu -mcpu="$2" -iterations=100 "$1" 2>/dev/null |
    awk '/^Iterations:/ { i = $2 } /^Total Cycles:/ { c = $3 } END { if (i > 0) printf "%.3f", c / i }'
}

# block_source VADDR SIZE BASE: the block's instructions as assembly llvm-mca reads: branch and
# address targets become a label at its start (llvm-mca repeats the block whatever they say).
block_source() {
  local start=$(((0x$1) - $3))
  echo "block:"
  "$objdump" -d --no-show-raw-insn --start-address="$start" --stop-address=$((start + 4 * $2)) \
    "$bench" | awk -F'\t' '
      /^ *[0-9a-f]+:\t/ {
        op = $2; args = $3
        sub(/ *\/\/.*/, "", args)
        if (args ~ /<[^>]*>/) { sub(/ *<[^>]*>/, "", args); sub(/(0x)?[0-9a-f]+$/, "block", args) }
        print "\t" op (args == "" ? "" : "\t" args)
      }'
}

rows=()
while read -r name stages settings; do
  [[ -z $name || $name == \#* ]] && continue
  [[ -n ${EPIPOLE_ARM_ROWS:-} && " $EPIPOLE_ARM_ROWS " != *" $name "* ]] && continue
  rows+=("$name $stages $settings")
done <tests/arm_counts/rows
((${#rows[@]} > 0)) || { echo "arm-mca: no row of tests/arm_counts/rows is in '$EPIPOLE_ARM_ROWS'" >&2; exit 2; }

json=""
printf '%-9s %14s %8s' row "insns/pair" covered
for model in "${models[@]}"; do printf ' %13s %6s' "$model cycles" IPC; done
printf '\n'
for row in "${rows[@]}"; do
  read -r name stages settings <<<"$row"
  read -r -a sets <<<"$settings"
  sets=("${sets[@]/\$\{EPIPOLE_DATA_DIR\}/${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}}")
  run 1 "$stages" "${sets[@]}"
  run 2 "$stages" "${sets[@]}"
  notes=$(jq -r '.notes | join("; ")' "$work/bench-1.json")
  if [[ $notes == *"detect: off"* ]]; then
    echo "arm-mca: $name left out: $notes" >&2
    continue
  fi
  total=$(($(<"$work/count-2") - $(<"$work/count-1")))
  # A pair's executions of each block: 2 pairs' minus 1 pair's; the hottest 90 %.
  awk -v total="$total" '
    FNR == NR { once[$4 " " $3] = $2; next }
    { e = $2 - once[$4 " " $3]; if (e > 0) print e * $3, e, $3, $4, $5 }
  ' "$work/blocks-1" "$work/blocks-2" | sort -rn |
    awk -v total="$total" 'sum < 0.9 * total { print; sum += $1 }' >"$work/hot"
  # Where the binary was loaded: the hottest block lies in its function, within 64 KiB of its
  # start, and the load address is 64 KiB aligned; every hot block must then lie in its own.
  read -r _ _ _ vaddr symbol <"$work/hot"
  address=$(awk -v s="$symbol" '$3 == s { print $1; exit }' "$work/symbols")
  [[ -n $address ]] || { echo "arm-mca: $symbol is not in $bench" >&2; exit 1; }
  base=$((((0x$vaddr) - address) & ~0xffff))
  : >"$out/blocks-$name.txt"
  covered=0
  declare -A cycles=()
  for model in "${models[@]}"; do cycles[$model]=0; done
  while read -r insns executions size vaddr symbol; do
    offset=$(((0x$vaddr) - base))
    if ! awk -v s="$symbol" -v o="$offset" '$3 == s && o >= $1 && o < $1 + $2 { found = 1 }
                                            END { exit !found }' "$work/symbols"; then
      echo "arm-mca: the block at $vaddr is not in $symbol (load address $base)" >&2
      exit 1
    fi
    block_source "$vaddr" "$size" "$base" >"$work/block.s"
    per=()
    for model in "${models[@]}"; do
      c=$(mca_cycles "$work/block.s" "$model")
      [[ -n $c ]] || break
      per+=("$c")
    done
    if ((${#per[@]} == ${#models[@]})); then
      covered=$((covered + insns))
      for i in "${!models[@]}"; do
        cycles[${models[$i]}]=$(awk -v a="${cycles[${models[$i]}]}" -v e="$executions" \
          -v c="${per[$i]}" 'BEGIN { printf "%.0f", a + e * c }')
      done
      echo "$insns $executions ${per[*]} $(c++filt "$symbol")" >>"$out/blocks-$name.txt"
    else
      echo "$insns $executions unreadable $(c++filt "$symbol")" >>"$out/blocks-$name.txt"
    fi
  done <"$work/hot"
  ((covered > 0)) || { echo "arm-mca: $name: llvm-mca read none of the hot blocks" >&2; exit 1; }
  entry="{\"name\": \"$name\", \"instructions\": $total, \"covered\": $covered"
  printf '%-9s %14d %7.1f%%' "$name" "$total" "$(awk -v c="$covered" -v t="$total" 'BEGIN { print 100 * c / t }')"
  for model in "${models[@]}"; do
    # The uncovered instructions at the covered blocks' rate.
    estimate=$(awk -v c="${cycles[$model]}" -v cov="$covered" -v t="$total" \
      'BEGIN { printf "%.0f", c * t / cov }')
    ipc=$(awk -v e="$estimate" -v t="$total" 'BEGIN { printf "%.2f", t / e }')
    entry+=", \"$model\": {\"cycles\": $estimate, \"ipc\": $ipc}"
    printf ' %13d %6s' "$estimate" "$ipc"
  done
  printf '\n'
  json+="${json:+, }$entry}"
  unset cycles
done
echo "{\"preset\": \"$preset\", \"models\": [\"${models[0]}\", \"${models[1]}\"], \"stages\": [$json]}" |
  jq . >"$out/arm-mca.json"
echo "arm-mca: $out/arm-mca.json"
