"""Repose: repose segmented CT/MRI scans (VTK filters for meshing, bone weights, skinning and
posed-volume resampling)."""
from .ReposeFilters import *  # noqa: F401,F403
from .ReposeVolume import *  # noqa: F401,F403
