#!/usr/bin/env bash
# Checks what the main job (scripts/run-demo.sh) wrote: the calibration's files, and for every
# scene of the simulated board its frame pairs, its pictures and a serial stream that the robot's
# end decoded without a single error, and each recording as an independent MCAP reader and ROS 2
# decoder read it (tests/clients/mcap-read.mjs), and the recording's replay: its results the
# recorded scene's (the same rectified pair and disparity pictures, byte for byte). Exits non-zero
# naming each thing that is missing or wrong.
#
#   scripts/check-demo.sh OUT_DIR
set -euo pipefail

out=${1:?usage: scripts/check-demo.sh OUT_DIR}
reader="$(cd "$(dirname "$0")/.." && pwd)/tests/clients/mcap-read.mjs"
problems=0
problem() {
  echo "check-demo: $*" >&2
  problems=$((problems + 1))
}
nonempty() {
  [[ -s $1 ]] || problem "$1 is missing or empty"
}

for f in rig.yaml report.json preview.png; do nonempty "$out/calibration/$f"; done

summary="$out/sim/summary.json"
if ! jq -e '.scenes | length > 0' "$summary" >/dev/null 2>&1; then
  problem "$summary is missing, not JSON or lists no scene"
  exit 1
fi

# check FILTER WHAT: the scene's summary ($s) must satisfy the jq FILTER.
check() { jq -e --arg type "$per_frame" "$1" <<<"$s" >/dev/null || problem "$scene: $2"; }

while read -r scene; do
  dir="$out/sim/$scene"
  s=$(jq -c --arg scene "$scene" '.scenes[] | select(.scene == $scene)' "$summary")
  # The message a frame pair publishes: the frame summary, or OBSTACLE_DISTANCE in MAVLink.
  per_frame=$(jq -r 'if .decoder.protocol == "mavlink" then "obstacle_distance" else "frame" end' <<<"$s")
  check '.frames > 0' "no frame pairs"
  check '(.received[$type] // 0) == .frames' \
    "$(jq -c '.frames' <<<"$s") pairs but not as many '$per_frame' messages decoded"
  check '.decoder.errors == 0' "the serial stream was not decoded without errors: $(jq -c .decoder <<<"$s")"
  check '.pictures | length > 0' "no pictures"
  check '.calibration == "yes"' "ran without its calibration"
  nonempty "$dir/serial.bin"
  tail -n 1 "$dir/serial.jsonl" 2>/dev/null | jq -e '.type == "decoder" and .errors == 0' >/dev/null 2>&1 ||
    problem "$dir/serial.jsonl does not end with an error-free decoder line"
  while read -r picture; do
    nonempty "$dir/$picture"
  done < <(jq -r '.pictures[]' <<<"$s")
  # Each recording, as Foxglove's and the MCAP project's own libraries read it: every topic of
  # every recorded pair, the calibration, health.
  while read -r recording; do
    [[ -n $recording ]] || continue
    if ! read=$(node "$reader" "$recording" 2 2>&1); then
      problem "$recording does not read: $read"
      continue
    fi
    delivered=$(jq '.outputs.mcap.delivered' <<<"$s")
    jq -e --argjson n "$delivered" '.profile == "ros2" and
      ([.statistics.channel_message_counts | to_entries[] |
        select(.key | startswith("/epipole/")) | .value == $n] | all and length == 9) and
      .statistics.channel_message_counts["/tf_static"] == 1 and
      .statistics.channel_message_counts["/diagnostics"] >= 1 and
      ([.attachments[].name] == ["calibration.yaml"])' <<<"$read" >/dev/null ||
      problem "$recording: not every topic of the $delivered recorded pairs, or no calibration: $(jq -c .statistics <<<"$read")"
    echo "check-demo: $scene: $recording: $(jq -r '"\(.statistics.message_count) messages on \(.statistics.channel_count) topics in \(.statistics.chunk_count) chunks, read and decoded"' <<<"$read")"
  done < <(jq -r '.recordings // [] | .[]' <<<"$s")
  # A rendered world: the last ground decoded against the world's exact truth (docs/vision.md).
  if jq -e '.truth' <<<"$s" >/dev/null; then
    nonempty "$dir/truth.yaml"
    nonempty "$dir/true_disparity.png"
    check '.last_ground.flags == 1 and
      ((.last_ground.height_mm - .truth.height_mm) | fabs) <= 25 and
      ((.last_ground.pitch_cdeg - .truth.pitch_cdeg) | fabs) <= 100 and
      ((.last_ground.roll_cdeg - .truth.roll_cdeg) | fabs) <= 100' \
      "the ground $(jq -c .last_ground <<<"$s") is not the world's $(jq -c .truth <<<"$s")"
    echo "check-demo: $scene: ground $(jq -r '"\(.last_ground.height_mm) mm high, pitch \(.last_ground.pitch_cdeg / 100) deg, roll \(.last_ground.roll_cdeg / 100) deg; truth \(.truth.height_mm | round) mm, \(.truth.pitch_cdeg | round / 100) deg, \(.truth.roll_cdeg | round / 100) deg"' <<<"$s")"
    # A rendered path: the odometry at its last pair against the exact path (docs/odometry.md).
    if jq -e '.odometry' <<<"$s" >/dev/null; then
      nonempty "$dir/trajectory.tum"
      nonempty "$dir/odometry.tum"
      nonempty "$dir/trajectory.png"
      check '.odometry.path_m >= 19.9 and .odometry.end_error_percent <= 1 and
        .odometry.end_heading_deg <= 1 and .odometry.lost == 0' \
        "the odometry $(jq -c .odometry <<<"$s") strays from the path"
      echo "check-demo: $scene: odometry $(jq -r '"\(.odometry.tracked) pairs tracked; at the last, \(.odometry.end_error_m * 1000 | round) mm (\(.odometry.end_error_percent * 100 | round / 100) % of \(.odometry.path_m * 10 | round / 10) m) and \(.odometry.end_heading_deg * 100 | round / 100) deg off the path"' <<<"$s")"
    fi
  fi
  echo "check-demo: $scene: $(jq -r --arg type "$per_frame" \
    '"\(.frames) pairs, \(.received[$type] // 0) \($type) messages decoded (\(.decoder.protocol), \(.decoder.errors) errors), \(.pictures | length) pictures"' <<<"$s")"
done < <(jq -r '.scenes[].scene' "$summary")

# The replay of the recording: the recorded scene's first pair again, rectified with the
# calibration the recording carries, the same disparity.
replay="$out/replay/summary.json"
if s=$(jq -ce '.scenes[0]' "$replay" 2>/dev/null); then
  scene=$(jq -r .scene <<<"$s")
  recorded=$(jq -r '.scenes[] | select(.recordings) | .scene' "$summary" | head -n 1)
  check '.frames > 0' "no frame pairs replayed"
  check '.calibration == "yes"' "replayed without the recording's calibration"
  check '.decoder.errors == 0' "the replay's serial stream was not decoded without errors"
  for picture in frame0-rectified-pair.png frame0-disparity16.png; do
    cmp -s "$out/sim/$recorded/$picture" "$out/replay/$scene/$picture" ||
      problem "replay $scene: $picture is not the recorded scene's ($recorded)"
  done
  echo "check-demo: replay $scene: $(jq -r '.frames' <<<"$s") pairs, the recorded $recorded scene's first rectified pair and disparity again"
else
  problem "$replay is missing or lists no scene"
fi

if ((problems > 0)); then
  echo "check-demo: $problems problems in $out" >&2
  exit 1
fi
echo "check-demo: $out is complete"
