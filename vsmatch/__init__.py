"""vsmatch: dense stereo matching guided by visual sensitive information.

Wang, Pathan and Dev, "Stereo Matching Based on Visual Sensitive Information", ICIVC 2021.
"""

from .config import Config, ConfigError, load_config
from .disparity import INVALID_DISPARITY
from .geometry import Calibration, depth_from_disparity, point_cloud, read_calibration
from .matcher import StereoMatcher
from .pipeline import MatchResult, match, run
from .search_range import estimate_disparity_range

__version__ = "0.5.0"

__all__ = ["Calibration", "Config", "ConfigError", "INVALID_DISPARITY", "MatchResult",
           "StereoMatcher", "__version__", "depth_from_disparity", "estimate_disparity_range",
           "load_config", "match", "point_cloud", "read_calibration", "run"]
