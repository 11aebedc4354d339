#!/usr/bin/env bash
# The paper's Table 2: accuracy under Gaussian noise of 2, 5, 10 and 15 % (3 seeds).
#   scripts/noise_sweep.sh [OUT_DIR] [SEEDS]
set -euo pipefail
# shellcheck source=scripts/_env.sh
. "$(dirname "$0")/_env.sh"
out="${1:-results}"
seeds="${2:-3}"
mkdir -p "$out"
vsmatch eval --dataset middlebury2 --method census --method paper --method default \
    --noise 0.02,0.05,0.10,0.15 --seeds "$seeds" --json "$out/noise.json"
