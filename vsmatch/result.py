"""What a match returns, and the timing of its stages."""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from . import noise, photometric
from .config import Config


@dataclass
class MatchResult:
    """The left-view disparity and what was learnt on the way."""

    disparity: np.ndarray
    labels: np.ndarray | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    config: Config | None = None  # as used at full size, after any noise adaptation
    noise_sigma: float | None = None  # of the input views, estimated when noise.adapt is on
    colour_weight: float = 1.0  # of the colour term, after the exposure correction
    levels: int = 0  # pyramid levels below the input where the full search ran
    stripes: int = 1  # stripes the full search ran in
    photometric: photometric.Correction | None = None  # the right view's colour map, if any
    search_range: tuple[int, int] | None = None  # (min_disp, max_disp) searched
    # How likely each disparity is right, in [0, 1] (vsmatch.confidence); float32 (H, W).
    confidence: np.ndarray | None = None
    # The cost-curve features the confidence is made from (vsmatch.confidence).
    curve: dict[str, np.ndarray] | None = None


@dataclass(frozen=True)
class Learnt:
    """What the pipeline learns of a pair before it matches it, decided once and given to
    every level's solver: the noise of the input views (None: no adaptation) and the colour
    term's weight the exposure correction leaves."""

    noise_sigma: float | None = None
    width: int = 0  # of the input views, to tell the pyramid level a solver works on
    colour_weight: float = 1.0

    def noise_at(self, width: int) -> float | None:
        """The noise of the views ``width`` pixels wide that pyramid levels down from the
        input's make (each level scales it by ``noise.LEVEL_NOISE_FACTOR``)."""
        if self.noise_sigma is None:
            return None
        levels = round(math.log2(self.width / width)) if self.width else 0
        return self.noise_sigma * noise.LEVEL_NOISE_FACTOR ** levels


def learn(left: np.ndarray, right: np.ndarray, cfg: Config, colour_weight: float = 1.0
          ) -> Learnt:
    """What every level's solver is given of a pair: with ``noise.adapt``, its noise,
    measured once, here, on the input views."""
    sigma = noise.estimate_pair_noise(left, right) if cfg.noise.adapt else None
    return Learnt(noise_sigma=sigma, width=left.shape[1], colour_weight=colour_weight)


@contextmanager
def timed(seconds: dict[str, float], name: str):
    """Add the time the block takes to ``seconds[name]``."""
    start = time.perf_counter()
    yield
    seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start
