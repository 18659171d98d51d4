"""Pictures of results: polyscope scenes, headless renders, matplotlib plots.

Contract: draws results (a mesh, a :class:`~igl_heatseg.segmentation.Segmentation`, charts);
never runs an algorithm. polyscope and matplotlib are the ``viz`` extra, imported when used.
"""

from .core import *  # noqa: F401,F403
from .core import __all__ as _core_all

__all__ = list(_core_all)
