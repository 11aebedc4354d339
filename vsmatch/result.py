"""What a match returns, and the timing of its stages."""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from . import photometric
from .config import Config


@dataclass
class MatchResult:
    """The left-view disparity and what was learnt on the way."""

    disparity: np.ndarray
    labels: np.ndarray | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    config: Config | None = None  # as used, after any noise adaptation
    noise_sigma: float | None = None  # estimated, when noise.adapt is on
    levels: int = 0  # pyramid levels below the input where the full search ran
    stripes: int = 1  # stripes the full search ran in
    photometric: photometric.Correction | None = None  # the right view's colour map, if any
    search_range: tuple[int, int] | None = None  # (min_disp, max_disp) searched
    # How likely each disparity is right, in [0, 1] (vsmatch.confidence); float32 (H, W).
    confidence: np.ndarray | None = None
    # The cost-curve features the confidence is made from (vsmatch.confidence).
    curve: dict[str, np.ndarray] | None = None
    exposed: Config | None = None  # the config after the exposure correction


@contextmanager
def timed(seconds: dict[str, float], name: str):
    """Add the time the block takes to ``seconds[name]``."""
    start = time.perf_counter()
    yield
    seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start
