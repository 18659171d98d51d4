"""Segmentation: seeds, heat rounds, labels (paper §3.1-3.4) and robust mode.

Contract: takes a :class:`~igl_heatseg.mesh.CleanMesh`; returns a :class:`Segmentation` (one
label per face, largest segment first, plus the intermediate results of the paper's figures).
Parameters are resolved and checked in one place (:mod:`.params`); ``paper`` and ``robust``
share the heat round and the eps rule. Imports ``heat`` and ``mesh`` only.
"""

from .api import segment, segment_with_mode
from .paper import Segmentation, segment_mesh
from .params import MODES, SOLVERS, check_segment_params, eps_keep, resolve_params
from .robust import RobustSegmentation, segment_robust

__all__ = [
    "Segmentation",
    "RobustSegmentation",
    "segment",
    "segment_mesh",
    "segment_robust",
    "segment_with_mode",
    "resolve_params",
    "check_segment_params",
    "eps_keep",
    "MODES",
    "SOLVERS",
]
