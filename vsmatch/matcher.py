"""A matcher made once for many frames of one camera: video, a robot's stream.

:class:`StereoMatcher` keeps what does not change between frames: the parsed config, a
raw rig's rectification maps, the disparity range found from the first frame (found
again when the scene comes closer than it allows) and the cost volumes' memory
(``vsmatch.volumes``). Each frame's result is the same as
:func:`vsmatch.match` gives for that frame and range.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import pipeline, rig, volumes
from .config import Config, load_config
from .disparity import INVALID_DISPARITY
from .geometry import Calibration, CalibrationError, read_calibration
from .search_range import resolve_range
from .temporal import Temporal

#: The range is found again when more than this share of a frame's confident pixels
#: lies within TOP_MARGIN of its top: something came closer than the range allows.
CROWDED_TOP_SHARE = 0.005
TOP_MARGIN = 2.0
#: Confidence above which a pixel counts for that.
CONFIDENT = 0.5


class StereoMatcher:
    """``StereoMatcher(max_disp=None, min_disp=0, config=None, calib=None, temporal=False)``.

    ``max_disp`` None finds the range from the first frame (and again when needed);
    ``calib`` is a rectified pair's calibration (a path or a :class:`Calibration`), or a
    raw rig's file(s), whose rectification is then applied to every frame. ``compute``
    gives the disparity, :meth:`result` everything (confidence, timings, range).
    ``temporal``: the frames are a stream; after the first (which is matched as alone),
    each searches near the last one's disparities and holds them where the image holds
    still (``vsmatch.temporal``). Off, every frame is matched alone.
    """

    def __init__(self, max_disp: int | None = None, min_disp: int | None = None,
                 config: Config | str | None = None, calib=None, alpha: float = 0.0,
                 temporal: bool = False):
        self.config = load_config(config)
        if not isinstance(temporal, bool):
            raise ValueError(f"temporal must be True or False, got {temporal!r}")
        self.temporal = Temporal() if temporal else None
        for name, value in (("max_disp", max_disp), ("min_disp", min_disp)):
            if value is not None and (isinstance(value, bool)
                                      or not isinstance(value, (int, np.integer))):
                raise ValueError(f"{name} must be a whole number or None, got {value!r}")
        if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not (
                0 <= alpha <= 1):
            raise ValueError(f"alpha must be a number from 0 to 1, got {alpha!r}")
        self.fixed_range = max_disp is not None
        self.min_disp = min_disp
        self.range = None if max_disp is None else (min_disp or 0, max_disp)
        self.camera: Calibration | None = None
        self._raw_rig = None
        self._rectifier = None
        self._alpha = alpha
        paths = [calib] if isinstance(calib, (str, Path)) else calib
        if calib is not None and not isinstance(calib, Calibration) and not (
                isinstance(paths, (list, tuple)) and paths
                and all(isinstance(p, (str, Path)) for p in paths)):
            raise ValueError("calib must be a Calibration, a calibration file's path or a "
                             f"list of one or two paths, got {calib!r}"[:200])
        if isinstance(calib, Calibration):
            self.camera = calib
        elif paths:
            if rig.is_raw_rig(paths):
                self._raw_rig = rig.read_rig(paths)
            else:
                self.camera = read_calibration(paths[0])
        self.frames = 0
        self.views: tuple[np.ndarray, np.ndarray] | None = None
        self._volumes = volumes.VolumePool()

    def rectify(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The views as matched: rectified with the rig's maps (made on the first frame)."""
        if self._raw_rig is None:
            problem = None if self.camera is None else self.camera.size_problem(left.shape)
            if problem is not None:
                raise CalibrationError(problem)
            return left, right
        if self._rectifier is None:
            self._rectifier = rig.Rectifier(self._raw_rig, left.shape[1::-1], self._alpha)
            self.camera = self._rectifier.calibration()
        return self._rectifier.rectify(left, right)

    def result(self, left: np.ndarray, right: np.ndarray) -> pipeline.MatchResult:
        """The whole :class:`vsmatch.pipeline.MatchResult` of one frame."""
        left, right = self.rectify(left, right)
        self.views = left, right  # as matched: a cloud's colours come from the left
        if self.range is None:
            self.range = self._find_range(left, right)
        low, high = self.range
        with volumes.reused(self._volumes):
            result = pipeline.run(left, right, max_disp=high, min_disp=low, config=self.config,
                                  temporal=self.temporal)
        self.frames += 1
        if not self.fixed_range and self._top_is_crowded(result, high):
            self.range = None  # the next frame looks for it again
        return result

    def empty_result(self, left: np.ndarray) -> pipeline.MatchResult:
        """A frame with no estimate (a stream's frame that gave no range): every pixel
        invalid and of confidence 0, in the views' size as matched."""
        shape = left.shape[:2]  # rectification keeps the size
        return pipeline.MatchResult(
            disparity=np.full(shape, INVALID_DISPARITY, np.float32),
            confidence=np.zeros(shape, np.float32), config=self.config)

    def reset(self) -> None:
        """Start a new stream: the next frame is matched as a first one (its range found
        again unless given)."""
        if self.temporal is not None:
            self.temporal.reset()
        if not self.fixed_range:
            self.range = None

    def compute(self, left: np.ndarray, right: np.ndarray) -> np.ndarray:
        """The left-view disparity of one frame (float32, inf = invalid)."""
        return self.result(left, right).disparity

    def _find_range(self, left, right) -> tuple[int, int]:
        """The calibration's range when it gives a real one, else the pair's, from
        ``min_disp`` when given (:func:`vsmatch.search_range.resolve_range`)."""
        searched = resolve_range(left, right, min_disp=self.min_disp, camera=self.camera,
                                 rectified_here=self._raw_rig is not None)
        return searched.min_disp, searched.max_disp

    @staticmethod
    def _top_is_crowded(result: pipeline.MatchResult, high: int) -> bool:
        confident = result.confidence >= CONFIDENT
        if not confident.any():
            return False
        near_top = confident & (result.disparity >= high - TOP_MARGIN)
        return near_top.sum() > CROWDED_TOP_SHARE * confident.sum()
