# Sourced by the other scripts: use the project's .venv, creating it on a fresh clone.
# shellcheck shell=bash
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if ! command -v vsmatch >/dev/null 2>&1; then
    if [ ! -x "$root/.venv/bin/vsmatch" ]; then
        echo "setting up $root/.venv (first run only)" >&2
        python3 -m venv "$root/.venv"
        "$root/.venv/bin/python" -m pip install --quiet -e "$root"
    fi
    # shellcheck disable=SC1091
    . "$root/.venv/bin/activate"
fi
export VSMATCH_DATA="${VSMATCH_DATA:-$root/../shared/data}"
