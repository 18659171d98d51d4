"""Mode dispatch: the one place a mode's parameters are resolved before segmenting."""

from __future__ import annotations

from numpy.typing import ArrayLike

from ..mesh.checks import CleanMesh, validate_mesh
from .paper import Progress, Segmentation, segment_mesh
from .params import check_solver, resolve_params
from .robust import segment_robust

__all__ = ["segment_with_mode", "segment"]


def segment_with_mode(
    mesh: CleanMesh,
    mode: str = "paper",
    theta: float | None = None,
    eps: float | None = None,
    *,
    progress: Progress | None = None,
    solver: str = "fast",
    keep_solvers: bool = False,
    refine: bool | None = None,
) -> Segmentation:
    """Segment in the paper's mode or in robust mode, with each mode's own defaults.

    Parameters
    ----------
    mesh : CleanMesh
    mode : {"paper", "robust"}
        ``"paper"``: :func:`~igl_heatseg.segmentation.paper.segment_mesh`, faithful to the
        paper. ``"robust"``: :func:`~igl_heatseg.segmentation.robust.segment_robust`.
    theta, eps : float, optional
        ``None`` takes the mode's default (:func:`~igl_heatseg.segmentation.params.resolve_params`).
    progress : callable(stage, fraction), optional
    solver : {"fast", "exact"}
        Heat solver (both modes).
    keep_solvers : bool
        Paper mode: keep the factorizations for :meth:`Segmentation.temperature`.
    refine : bool, optional
        Robust mode: refine the segments by their surface fits; default on exact CAD
        tessellations only (:func:`~igl_heatseg.segmentation.robust.segment_robust`); ignored
        in paper mode.

    Returns
    -------
    Segmentation

    Raises
    ------
    MeshError
        Unknown mode or solver, or parameters out of range.
    """
    theta, eps = resolve_params(mode, theta, eps)
    check_solver(solver)
    if mode == "paper":
        return segment_mesh(
            mesh, theta, eps, progress=progress, solver=solver, keep_solvers=keep_solvers
        )
    return segment_robust(mesh, theta, eps, solver=solver, progress=progress, refine=refine)


def segment(
    V: ArrayLike,
    F: ArrayLike | None = None,
    theta: float | None = None,
    eps: float | None = None,
    *,
    mode: str = "paper",
    solver: str = "fast",
    progress: Progress | None = None,
    refine: bool | None = None,
) -> Segmentation:
    """Segment a mesh: the package's main entry point.

    Parameters
    ----------
    V : (n, 3) array_like of float, or CleanMesh
        Vertex positions, or an already validated mesh (then ``F`` is ``None``).
    F : (m, 3) array_like of int, optional
        Triangles (validated here).
    theta, eps : float, optional
        ``None``: the mode's defaults (paper: pi/20 and 0.05, Table 1).
    mode : {"paper", "robust"}
    solver : {"fast", "exact"}
    progress : callable(stage, fraction), optional
    refine : bool, optional
        Robust mode: refine the segments by their surface fits (default: on exact CAD
        tessellations only).

    Returns
    -------
    Segmentation
        ``labels (m,) int64`` ``0..k-1``, largest segment first, in the input face order.

    Examples
    --------
    >>> import igl, igl_heatseg as ih
    >>> V, F = igl.icosahedron()
    >>> V, F = igl.loop(V, F, 4)       # a fine sphere: no edge is sharp, one segment
    >>> ih.segment(V, F).num_segments
    1
    """
    mesh = V if isinstance(V, CleanMesh) and F is None else validate_mesh(V, F)
    return segment_with_mode(mesh, mode, theta, eps, progress=progress, solver=solver,
                             refine=refine)
