#!/usr/bin/env bash
# The main job: installs what is missing, fetches the data sets, builds the host tool and runs
# Epipole's stages on real stereo images, writing pictures and JSON a person can look at:
#   - the chessboard rig (13 pairs): stereo calibration -> rig.yaml, report.json, preview.png;
#     then left01/right01 rectified with it, as the firmware would (rectified-pair.png);
#   - corners (FAST and Harris) on the rectified left view;
#   - Middlebury Aloe: dense disparity, quality (SGM) and fast (BM), 16-bit PNG + colour picture.
#
#   scripts/run-demo.sh [OUT_DIR]      (default: out/demo)
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-out/demo}
data=${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}
samples="$data/samples"

./scripts/setup.sh
./scripts/fetch-data.sh
cmake --preset host >/dev/null
cmake --build --preset host --target epipole
tool=build/host/host-tools/epipole

mkdir -p "$out"
echo "demo: $("$tool" --version)"

echo "demo: calibrating the chessboard rig"
"$tool" calibrate --left "$samples/left[0-9][0-9].jpg" --right "$samples/right[0-9][0-9].jpg" \
  --board chessboard:9x6 --square 0.025 -o "$out/rig.yaml" --report "$out/calibration-report.json" \
  --preview "$out/calibration-preview.png"

echo "demo: rectifying left01/right01 with it"
"$tool" rectify "$samples/left01.jpg" "$samples/right01.jpg" --calib "$out/rig.yaml" \
  --out-left "$out/left01-rectified.png" --out-right "$out/right01-rectified.png" \
  --preview "$out/rectified-pair.png"

for detector in fast harris; do
  echo "demo: $detector corners: $("$tool" features "$out/left01-rectified.png" --detector "$detector" \
    --max 100000 --draw "$out/left01-$detector.png")"
  "$tool" features "$out/left01-rectified.png" --detector "$detector" --max 100000 --json \
    >"$out/left01-$detector.json"
done

for method in sgm bm; do
  echo "demo: Aloe disparity ($method): $("$tool" disparity "$samples/aloeL.jpg" "$samples/aloeR.jpg" \
    --max-disparity 256 --method "$method" --out "$out/aloe-disparity-$method.png" \
    --color "$out/aloe-disparity-$method-color.png")"
done

echo "demo: sparse matches of left01/right01 in 3-D: $("$tool" match "$samples/left01.jpg" \
  "$samples/right01.jpg" --calib "$out/rig.yaml" --detector harris --max-disparity 128 \
  --draw "$out/left01-matches.png")"
"$tool" match "$samples/left01.jpg" "$samples/right01.jpg" --calib "$out/rig.yaml" \
  --detector harris --max-disparity 128 --json >"$out/left01-points.json"
echo "demo: Aloe sparse matches: $("$tool" match "$samples/aloeL.jpg" "$samples/aloeR.jpg" \
  --max-disparity 256 --draw "$out/aloe-matches.png")"

echo "demo: pictures and JSON in $out/"
ls "$out"
