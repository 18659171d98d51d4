"""CAD stage: a segmented mesh with one fitted surface per segment to a sewn B-Rep and STEP.

Contract: takes a validated, consistently oriented manifold triangle mesh (``V (n,3)
float64``, ``F (m,3) int64``, outward when closed), face ``labels (m,) int64`` in ``0..k-1``
(each segment face-connected), ``k`` :class:`igl_heatseg.surfaces.model.Surface` objects and
optional per-segment UV charts; returns a :class:`CadResult` (OCC shape, per-face status,
fidelity, timings). Faces that cannot be built are faceted and reported, never raised.
Imports only :mod:`igl_heatseg.errors`, :mod:`igl_heatseg.mesh` and
:mod:`igl_heatseg.surfaces` from the package (:mod:`.segments` fits surfaces to segments that
have none, and turns pipeline charts, taken by duck typing, into the ``uv`` argument).

OpenCASCADE (``OCP``) is an optional dependency, imported when a name of this subpackage is
first used; without it an ImportError says ``pip install 'igl_heatseg[cad]'``.
"""

from __future__ import annotations

import importlib

__all__ = ["build_brep", "CadResult", "write_step", "read_step", "brep_fidelity",
           "tessellate_by_type", "fit_segment_surfaces", "chart_uvs"]

_WHERE = {
    "build_brep": "build",
    "CadResult": "build",
    "write_step": "step",
    "read_step": "step",
    "brep_fidelity": "fidelity",
    "tessellate_by_type": "fidelity",
    "fit_segment_surfaces": "segments",
    "chart_uvs": "segments",
}


def __getattr__(name):
    if name in _WHERE:
        from ._ocp import require_ocp

        require_ocp()
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
