#!/usr/bin/env bash
# The main job: installs what is missing, fetches the data sets, builds the host tool and runs
# Epipole's stages on real stereo images, writing pictures and JSON a person can look at.
#
#   scripts/run-demo.sh [OUT_DIR]      (default: out/demo)
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-out/demo}
data=${EPIPOLE_DATA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data}

./scripts/setup.sh
./scripts/fetch-data.sh
cmake --preset host >/dev/null
cmake --build --preset host --target epipole
tool=build/host/host-tools/epipole

mkdir -p "$out"
echo "demo: $("$tool" --version)"
# The chessboard stereo rig (640x480) and Middlebury Aloe (1282x1110), left and right views.
for image in left01 right01 aloeL aloeR; do
  input="$data/samples/$image.jpg"
  summary=$("$tool" features "$input" --detector fast --threshold 20 --max 100000 \
    --draw "$out/$image-fast.png")
  "$tool" features "$input" --detector fast --threshold 20 --max 100000 --json >"$out/$image-fast.json"
  echo "demo: $image: $summary"
done
echo "demo: pictures and JSON in $out/"
ls "$out"
