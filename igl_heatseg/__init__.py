"""igl_heatseg: heat-based mesh segmentation for reverse engineering, built on libigl."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from .checks import CleanMesh, validate_mesh
from .constants import EPS_DEFAULT, THETA_DEFAULT
from .errors import MeshError

try:
    __version__ = version("igl_heatseg")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0+unknown"

__all__ = [
    "MeshError",
    "CleanMesh",
    "validate_mesh",
    "THETA_DEFAULT",
    "EPS_DEFAULT",
    "__version__",
]
