"""The surface fits under their former module name: re-exports only.

The code lives in one module per topic:

* :mod:`~igl_heatseg.surfaces.primitives` — the plane, sphere, cylinder, cone and torus fits
  and their seeds;
* :mod:`~igl_heatseg.surfaces.lm` — Levenberg-Marquardt and the numerical helpers the fits share;
* :mod:`~igl_heatseg.surfaces.select` — :func:`fit_surface` (the simplest kind within
  tolerance), :func:`surface_residual`, :func:`within_tolerance`;
* :mod:`~igl_heatseg.surfaces.tolerance` — :func:`noise_level`, :func:`fit_tolerance`;
* :mod:`~igl_heatseg.surfaces.samples` — :func:`face_samples`, :func:`face_residuals`;
* :mod:`~igl_heatseg.surfaces.checks` — input validation.
"""

from __future__ import annotations

from .primitives import fit_cone, fit_cylinder, fit_plane, fit_sphere, fit_torus
from .samples import face_residuals, face_samples
from .select import fit_surface, surface_residual, within_tolerance
from .tolerance import fit_tolerance, noise_level

__all__ = [
    "fit_plane",
    "fit_sphere",
    "fit_cylinder",
    "fit_cone",
    "fit_torus",
    "fit_surface",
    "surface_residual",
    "within_tolerance",
    "face_samples",
    "face_residuals",
    "noise_level",
    "fit_tolerance",
]
