#!/usr/bin/env bash
# Match every stereo pair in a folder (sub-folders with imL/imR, im0/im1, view1/view5 or
# left/right images, or NAME_left / NAME_right files side by side).
#   scripts/match_folder.sh SCENES_DIR [OUT_DIR] [extra vsmatch batch options...]
# Example: scripts/match_folder.sh ../shared/data/middlebury2 disparities --max-disp 59 --jobs 2
set -euo pipefail
if [ $# -lt 1 ]; then
    echo "usage: $0 SCENES_DIR [OUT_DIR] [vsmatch batch options...]" >&2
    exit 2
fi
# shellcheck source=scripts/_env.sh
. "$(dirname "$0")/_env.sh"
src="$1"; shift
out="${1:-disparities}"; [ $# -gt 0 ] && shift
vsmatch batch "$src" -o "$out" "$@"
