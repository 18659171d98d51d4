"""Surface recovery: one fitted surface (plane, cylinder, cone, sphere, torus or freeform) per
segment, and the fit-driven refinement of a segmentation into the part's faces.

Contract: takes a validated mesh (``V (n,3) float64``, ``F (m,3) int64``) and face labels;
returns :class:`Surface` objects and new labels. Imports only from ``mesh`` and below.
"""

from .model import ANALYTIC_KINDS, SURFACE_KINDS, Surface

__all__ = ["SURFACE_KINDS", "ANALYTIC_KINDS", "Surface"]
