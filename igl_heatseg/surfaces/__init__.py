"""Surface recovery: one fitted surface (plane, cylinder, cone, sphere, torus or freeform) per
segment, and the fit-driven refinement of a segmentation into the part's faces.

Contract: takes a validated mesh (``V (n,3) float64``, ``F (m,3) int64``) and face labels;
returns :class:`Surface` objects and new labels. Imports only from ``mesh`` and below.
"""

from .model import ANALYTIC_KINDS, SURFACE_KINDS, Surface
from .primitives import fit_cone, fit_cylinder, fit_plane, fit_sphere, fit_torus
from .refine import SurfaceSegmentation, refine_segmentation, segment_adjacency
from .samples import face_residuals, face_samples
from .segment_fit import fit_segments
from .select import fit_surface, surface_residual, within_tolerance
from .tolerance import fit_tolerance, noise_level, vertex_tolerance

__all__ = ["SURFACE_KINDS", "ANALYTIC_KINDS", "Surface", "fit_plane", "fit_sphere",
           "fit_cylinder", "fit_cone", "fit_torus", "fit_surface", "surface_residual",
           "within_tolerance", "face_samples", "face_residuals", "noise_level", "fit_tolerance",
           "vertex_tolerance", "SurfaceSegmentation", "refine_segmentation", "fit_segments",
           "segment_adjacency"]
