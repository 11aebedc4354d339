"""vsmatch: dense stereo matching guided by visual sensitive information.

Wang, Pathan and Dev, "Stereo Matching Based on Visual Sensitive Information", ICIVC 2021.
"""

from .config import Config, ConfigError, load_config
from .disparity import INVALID_DISPARITY
from .pipeline import match

__version__ = "0.1.0"

__all__ = ["Config", "ConfigError", "INVALID_DISPARITY", "load_config", "match", "__version__"]
