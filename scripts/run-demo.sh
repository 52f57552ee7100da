#!/usr/bin/env bash
# The main job: installs what is missing, fetches the data sets, builds the firmware and the host
# tool, then
#   1. calibrates the chessboard stereo rig from its 13 pairs (rig.yaml, a JSON report and a
#      rectified preview), as a user does before flashing a board;
#   2. runs the firmware on the simulated board over real stereo images (epipole sim): the
#      chessboard rig with its calibration, Middlebury Aloe, a synthetic pair with faces at a
#      known depth, a rendered floor with boxes, and a rendered room walked round a 5 m square
#      (its whole path; the odometry drawn over the exact path in sim/loop/trajectory.png). For
#      each scene: the rectified pair with epipolar lines, corners, colour
#      disparity with a legend, the raw serial stream as the robot received it and its decoded
#      messages (serial.jsonl), and a summary; the chessboard scene is also recorded, every pair,
#      as ROS 2 messages in an MCAP file (docs/outputs.md) that Foxglove, Lichtblick and ros2 bag
#      open;
#   3. replays that recording as a scene (its raw pairs and the calibration it carries), as a user
#      replays what the robot saw: the same results again (scripts/check-demo.sh compares them).
#
#   scripts/run-demo.sh [OUT_DIR]      (default: out/demo)
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-out/demo}
data=${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}
samples="$data/samples"

./scripts/setup.sh
./scripts/fetch-data.sh
# The same data folder for the build (it compiles board/sim's face cascade into it) and the runs.
cmake --preset host -DEPIPOLE_DATA_DIR="$data" >/dev/null
cmake --build --preset host --target epipole epipole-fw sim_board_cascade
tool=build/host/host-tools/epipole

mkdir -p "$out/calibration"
echo "demo: $("$tool" --version)"

echo "demo: calibrating the chessboard rig"
"$tool" calibrate --left "$samples/left[0-9][0-9].jpg" --right "$samples/right[0-9][0-9].jpg" \
  --board chessboard:9x6 --square 0.025 -o "$out/calibration/rig.yaml" \
  --report "$out/calibration/report.json" --preview "$out/calibration/preview.png"

echo "demo: the firmware on the simulated board (board/sim)"
"$tool" sim --board board/sim --pictures 2 --record chessboard --out "$out/sim"
shopt -s nullglob
recordings=("$out"/sim/chessboard/recordings/*.mcap)
shopt -u nullglob
((${#recordings[@]} > 0)) || { echo "demo: the chessboard scene left no recording" >&2; exit 1; }
for recording in "${recordings[@]}"; do
  echo "demo: the chessboard scene's recording: $recording"
  echo "      open it in Foxglove or Lichtblick (Open local file), or: ros2 bag info $recording"
done

echo "demo: replaying the recording as a scene"
echo "      $tool sim --board board/sim --replay ${recordings[0]} --out $out/replay"
"$tool" sim --board board/sim --frames 60 --pictures 2 --replay "${recordings[0]}" \
  --out "$out/replay"

echo "demo: pictures, serial streams and summaries in $out/"
find "$out" -type f | sort
