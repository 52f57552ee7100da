#!/usr/bin/env bash
# A long fuzzing campaign by hand: every libFuzzer target of the fuzz build (label fuzz), one
# after another, each with the command line the test command gives it (its seeds, its
# dictionary, the working corpus kept between runs, a fresh random seed) but for RUNS
# executions or SECONDS, whichever comes first. Prints one line per target (executions, time,
# executions per second, new corpus size) and exits 1 if any target found a crash (its input is
# in build/fuzz/tests/fuzz/crash-<target>-...). docs/testing.md has the figures of the last
# campaign.
#
#   scripts/fuzz-campaign.sh [RUNS [SECONDS [TARGET_REGEX]]]   default 10000000 3600 .
#   (cmake --preset fuzz && cmake --build --preset fuzz first)
set -euo pipefail
cd "$(dirname "$0")/.."

runs=${1:-10000000}
seconds=${2:-3600}
filter=${3:-.}
build=build/fuzz
logs=$build/fuzz-campaign
[[ -d $build ]] || { echo "fuzz-campaign: no $build: cmake --preset fuzz && cmake --build --preset fuzz" >&2; exit 2; }
mkdir -p "$logs"

failed=0
printf '%-22s %12s %8s %10s %8s  %s\n' target executions seconds 'exec/s' corpus result
while IFS=$'\t' read -r name command; do
  [[ $name =~ $filter ]] || continue
  eval "args=($command)"
  log=$logs/$name.log
  status=0
  "${args[@]}" "-runs=$runs" "-max_total_time=$seconds" -print_final_stats=1 >"$log" 2>&1 ||
    status=$?
  done_line=$(grep -E '^Done [0-9]+ runs in [0-9]+ second' "$log" | tail -1 || true)
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  spent=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' <<<"$done_line")
  corpus=$(sed -n 's/^#[0-9]*.*corp: \([0-9]*\)\/.*/\1/p' "$log" | tail -1)
  result=ok
  if ((status != 0)) || [[ -z $done_line ]]; then
    result="FAILED (exit $status): $log"
    failed=1
  fi
  rate=$(( ${spent:-0} > 0 ? ${executions:-0} / spent : ${executions:-0} ))
  printf '%-22s %12s %8s %10s %8s  %s\n' "$name" "${executions:-?}" "${spent:-?}" "$rate" \
    "${corpus:-?}" "$result"
done < <(ctest --test-dir "$build" -L fuzz --show-only=json-v1 |
  jq -r '.tests[] | [.name, (.command | map(@sh) | join(" "))] | @tsv')
exit $failed
