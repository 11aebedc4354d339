"""vsmatch: dense stereo matching guided by visual sensitive information.

Wang, Pathan and Dev, "Stereo Matching Based on Visual Sensitive Information", ICIVC 2021.

The names below are imported when first used, so that ``import vsmatch`` (and the
``vsmatch`` command's start, where Ctrl-C must stay one line) does not load Numba and
OpenCV before they are needed.
"""

from __future__ import annotations

import importlib

__version__ = "0.5.0"

#: Each public name and the module that defines it.
_EXPORTS = {
    "Calibration": "geometry", "Config": "config", "ConfigError": "config",
    "ForkedProcessError": "forking",
    "INVALID_DISPARITY": "disparity", "MatchResult": "result", "StereoMatcher": "matcher",
    "depth_from_disparity": "geometry", "estimate_disparity_range": "search_range",
    "load_config": "config", "match": "api", "point_cloud": "geometry",
    "read_calibration": "geometry", "run": "api",
}

__all__ = sorted([*_EXPORTS, "__version__"])


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vsmatch' has no attribute '{name}'")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # found directly from now on
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
