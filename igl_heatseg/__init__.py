"""igl_heatseg: from a triangle mesh of a mechanical part to the surfaces of its CAD model.

The stages, each a subpackage (imports only go down this list):

``mesh``              the validated boundary (:func:`validate_mesh`) and mesh primitives
``io``                mesh readers (:func:`load_mesh`) and result writers
``heat``              harmonic temperature fields (:class:`HeatSolver`, :class:`FastHeatSolver`)
``segmentation``      the paper's segmentation (:func:`segment`) and robust mode
``surfaces``          fitted surfaces (:class:`Surface`)
``parameterization``  cut to disks, Hessian eigenmaps, certificates, atlas packing
``pipeline``          :func:`run`: segment, cut, parameterize, pack
``evaluation``        scores against ground truth (loaded on first use)
``viz``               polyscope scenes and plots (loaded on first use; ``viz`` extra)

Examples
--------
>>> import igl, igl_heatseg as ih
>>> V, F = igl.icosahedron()
>>> mesh = ih.validate_mesh(*igl.loop(V, F, 3))
>>> ih.segment(mesh).num_segments
1
"""

from __future__ import annotations

import importlib

from .constants import EPS_DEFAULT, THETA_DEFAULT
from .errors import MeshError
from .heat import FastHeatSolver, HeatSolver, heat_fields
from .io import load_mesh
from .mesh import CleanMesh, validate_mesh
from .parameterization import CutError, certify_map, cut_to_disk, parameterize_chart
from .pipeline import PipelineResult, run_pipeline
from .segmentation import Segmentation, segment, segment_mesh, segment_robust
from .surfaces import Surface
from .version import __version__

#: ``ih.run`` is the pipeline: segment, cut to disks, parameterize, pack.
run = run_pipeline

__all__ = [
    "load_mesh",
    "validate_mesh",
    "CleanMesh",
    "MeshError",
    "CutError",
    "segment",
    "segment_mesh",
    "segment_robust",
    "Segmentation",
    "HeatSolver",
    "FastHeatSolver",
    "heat_fields",
    "parameterize_chart",
    "cut_to_disk",
    "certify_map",
    "run",
    "run_pipeline",
    "PipelineResult",
    "Surface",
    "THETA_DEFAULT",
    "EPS_DEFAULT",
    "__version__",
    "viz",
    "evaluation",
]

#: Subpackages imported on first attribute access (PEP 562), so that ``import igl_heatseg``
#: never pulls in polyscope or matplotlib.
_LAZY = ("viz", "evaluation", "cad", "batch", "cli")


def __getattr__(name: str):
    if name in _LAZY:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'igl_heatseg' has no attribute {name!r}")
