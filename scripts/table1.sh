#!/usr/bin/env bash
# Reproduce the paper's Table 1 and the README's results tables: census baseline, the
# paper's method and vsmatch's default on middlebury2 and on the 2005/2006 scenes; default
# and OpenCV SGBM on Middlebury 2014 (quarter size) and KITTI 2015.
#   scripts/table1.sh [OUT_DIR]   (JSON reports, disparities and error images go there)
set -euo pipefail
# shellcheck source=scripts/_env.sh
. "$(dirname "$0")/_env.sh"
out="${1:-results}"
mkdir -p "$out"
for dataset in middlebury2 middlebury-third; do
    vsmatch eval --dataset "$dataset" --method census --method paper --method default \
        --json "$out/$dataset.json" --out-dir "$out/$dataset"
done
for dataset in middlebury2014-quarter kitti2015; do
    vsmatch eval --dataset "$dataset" --method default --method opencv-sgbm \
        --json "$out/$dataset.json" --out-dir "$out/$dataset" --figure "$out/$dataset.png"
done
