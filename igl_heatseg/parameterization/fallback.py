"""Bijective fallbacks: mean-value Tutte map, local repair, guarded SLIM.

- :func:`tutte_map`: a convex-combination map (Floater's mean value weights, boundary on a
  circle by arc length), bijective by construction (Tutte, Floater).
- :func:`repair_map`: a Hessian map with only local defects (flips, no boundary overlap) has a
  small region around them re-solved harmonically, growing ring by ring.
- :func:`slim_guarded`: SLIM (symmetric Dirichlet, free boundary or boundary held) one
  iteration at a time with the certificate after each, keeping the last bijective iterate.
"""

from __future__ import annotations

import logging
from typing import Literal

import igl
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..mesh.topology import boundary_loops
from .bijectivity import Certificate, certify_map
from .distortion import distortion
from .prepare import certify_oriented, unique_edges

__all__ = [
    "tutte_map",
    "mean_value_laplacian",
    "circle_boundary",
    "repair_map",
    "slim_guarded",
    "slim_map",
    "SLIM_ITERATIONS",
    "REPAIR_ROUNDS",
    "REPAIR_MAX_FRACTION",
    "REPAIR_MIN_FREE",
    "REPAIR_MAX_SD_RATIO",
    "SLIM_STOP_AFTER_BAD",
    "SLIM_SOFT_P",
]

log = logging.getLogger(__name__)

#: SLIM iterations of the Tutte fallback's improvement.
SLIM_ITERATIONS: int = 30

#: Steps of iterative refinement of the Tutte solve (``x += solve(b - A x)``). A Tutte map
#: collapses parts of a noisy chart to triangles of round-off size, so whether it certifies
#: depends on the solver's last bits: on this machine (2026-12-01) the uniform-weight map of
#: ``data/chart_mean_value_tutte_flips.npz`` flipped 11 triangles without refinement and none
#: with it, where an earlier machine certified it unrefined.
TUTTE_REFINE_STEPS: int = 3

#: Local repair of a Hessian map with a few flips: rounds of growing the free region by one
#: ring around the offending vertices (uniform-weight harmonic re-solve of the free region).
REPAIR_ROUNDS: int = 4

#: The repair gives up when its free region would exceed this fraction of the vertices (or
#: :data:`REPAIR_MIN_FREE` vertices, whichever is larger).
REPAIR_MAX_FRACTION: float = 0.2
REPAIR_MIN_FREE: int = 64

#: A repaired Hessian map is kept only if its symmetric Dirichlet energy is at most this
#: factor above the (flipped) Hessian map's: a repair must not damage the map.
REPAIR_MAX_SD_RATIO: float = 1.05

#: Guarded SLIM stops after this many consecutive non-bijective iterates that follow a
#: bijective one (see :func:`slim_guarded`).
SLIM_STOP_AFTER_BAD: int = 3

#: Soft-constraint weight holding the boundary in the fixed-boundary SLIM variant.
SLIM_SOFT_P: float = 1e5


def circle_boundary(V: np.ndarray, bnd: np.ndarray) -> np.ndarray:
    """Boundary vertices on the unit circle, spacing by arc length, counter-clockwise.

    Examples
    --------
    >>> import numpy as np
    >>> P = circle_boundary(np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]), np.arange(4))
    >>> np.round(P, 12).tolist()
    [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [-0.0, -1.0]]
    """
    seg = np.linalg.norm(V[np.roll(bnd, -1)] - V[bnd], axis=1)
    t = np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    ang = 2.0 * np.pi * t
    return np.stack([np.cos(ang), np.sin(ang)], axis=1)


def tutte_map(
    V: np.ndarray,
    F: np.ndarray,
    bnd: np.ndarray | None = None,
    weights: Literal["mean_value", "uniform"] = "mean_value",
) -> np.ndarray:
    """Convex-combination (Tutte/Floater) map with the boundary on a circle.

    Every interior vertex is a positive-weight average of its neighbours; the boundary goes to
    the unit circle, spaced by arc length.  With positive weights and a strictly convex
    boundary the map of a triangulated disk is bijective (Tutte 1963, Floater 2003), up to
    floating-point rounding of the linear solve (the certificate checks it).  Floater's mean
    value weights (default) follow the 3D geometry: on sliver-rich CAD tessellations they gave
    a symmetric Dirichlet energy of 5.6e3 where uniform weights gave 5e22 (abc_stl2_00000008).

    Parameters
    ----------
    V : (n, 3) float64
        Vertices.
    F : (m, 3) int64
        Disk triangulation using every vertex.
    bnd : (b,) int64, optional
        Ordered boundary loop (surface on the left); computed when omitted.
    weights : {"mean_value", "uniform"}
        Floater's mean value weights or Tutte's uniform weights.

    Returns
    -------
    UV : (n, 2) float64
        Counter-clockwise image in the unit disk.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> UV = tutte_map(V, F)
    >>> from igl_heatseg.parameterization.bijectivity import certify_map
    >>> certify_map(UV, F).bijective
    True
    """
    n = V.shape[0]
    if bnd is None:
        bnd = boundary_loops(F)[0]
    if weights == "mean_value":
        L = mean_value_laplacian(V, F)
    else:
        E = unique_edges(F)
        A = sp.csr_matrix(
            (np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])),
            shape=(n, n),
        )
        L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
    UV = np.zeros((n, 2))
    UV[bnd] = circle_boundary(V, bnd)
    inner = np.setdiff1d(np.arange(n), bnd)
    if len(inner):
        LII = L[inner][:, inner].tocsc()
        rhs = -(L[inner][:, bnd] @ UV[bnd])
        solve = spla.factorized(LII)
        for c in range(2):  # refined: a collapsed region's triangles are round-off small
            x = solve(rhs[:, c])
            for _ in range(TUTTE_REFINE_STEPS):
                x = x + solve(rhs[:, c] - LII @ x)
            UV[inner, c] = x
        if weights == "mean_value" and not np.all(np.isfinite(UV)):
            return tutte_map(V, F, bnd, "uniform")
    return UV


def mean_value_laplacian(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    """(n, n) ``diag(rowsum W) - W`` with Floater's mean value weights (positive, asymmetric)
    ``W[i, j] = (tan(a/2) + tan(b/2)) / |x_i - x_j|``, ``a, b`` the angles at ``i`` next to
    the edge ``(i, j)``.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> L = mean_value_laplacian(V, F)
    >>> float(np.abs(L @ V[:, 0])[[5, 6, 9, 10]].max()) < 1e-12  # linear precision inside
    True
    """
    n = V.shape[0]
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, k = F[:, c], F[:, (c + 1) % 3], F[:, (c + 2) % 3]
        eij = V[j] - V[i]
        eik = V[k] - V[i]
        lij = np.linalg.norm(eij, axis=1)
        lik = np.linalg.norm(eik, axis=1)
        cosa = np.clip((eij * eik).sum(1) / np.maximum(lij * lik, 1e-300), -1.0, 1.0)
        t = np.tan(0.5 * np.arccos(cosa))
        rows += [i, i]
        cols += [j, k]
        vals += [t / np.maximum(lij, 1e-300), t / np.maximum(lik, 1e-300)]
    W = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )
    return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()


def repair_map(
    UV: np.ndarray,
    V: np.ndarray,
    F: np.ndarray,
    cert: Certificate,
    name: str = "chart",
    rounds: int = REPAIR_ROUNDS,
    max_fraction: float = REPAIR_MAX_FRACTION,
) -> tuple[np.ndarray, Certificate, int]:
    """Untangle a map with a few local flips by re-solving a small region harmonically.

    The free region starts as the vertices of the flipped and degenerate triangles (and wound
    vertices) and grows by one ring per round; its vertices are re-solved as the mean value
    (Floater) weighted average of their neighbours, weights from the 3D triangles, with every
    other vertex fixed.  Stops at the first
    round whose certificate is bijective.  Boundary overlaps are not repaired (returned as is).

    Parameters
    ----------
    UV : (n, 2) float64
        Map with the dominant orientation counter-clockwise.
    V : (n, 3) float64
        Chart vertices (for the weights).
    F : (m, 3) int64
        Triangles.
    cert : Certificate
        Certificate of ``UV``.

    Returns
    -------
    UV : (n, 2) float64
        Repaired map (the input where nothing was changed).
    cert : Certificate
        Its certificate.
    rounds : int
        Rounds used (0: nothing to do or overlaps).

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(7.0), np.arange(7.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(49).reshape(7, 7)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 8], 1), np.stack([i, i + 8, i + 7], 1)])
    >>> from igl_heatseg.parameterization.bijectivity import certify_map
    >>> UV = V[:, :2].copy()
    >>> UV[24] = [4.3, 4.2]  # the centre vertex pushed over its neighbours
    >>> cert = certify_map(UV, F)
    >>> cert.flips, cert.overlaps
    (2, 0)
    >>> UVr, cert_r, rounds = repair_map(UV, V, F, cert)
    >>> cert_r.bijective, rounds
    (True, 1)
    """
    n = UV.shape[0]
    if cert.bijective or cert.overlaps > 0:
        return UV, cert, 0
    E = unique_edges(F)
    A = sp.csr_matrix(
        (np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n)
    )
    L = mean_value_laplacian(V, F)
    free = np.zeros(n, dtype=bool)
    free[F[np.r_[cert.flipped_faces, cert.degenerate_faces]].ravel()] = True
    free[cert.wound_vertices] = True
    best_UV, best_cert = UV, cert
    for r in range(1, rounds + 1):
        free = free | (A @ free.astype(np.float64) > 0)
        if free.sum() > max(max_fraction * n, REPAIR_MIN_FREE) or (~free).sum() < 3:
            break
        fi = np.flatnonzero(free)
        fx = np.flatnonzero(~free)
        rhs = -(L[fi][:, fx] @ UV[fx])
        solve = spla.factorized(L[fi][:, fi].tocsc())
        UVr = UV.copy()
        UVr[fi, 0] = solve(rhs[:, 0])
        UVr[fi, 1] = solve(rhs[:, 1])
        c = certify_map(UVr, F, name=name)
        if c.mirrored:  # the repair never mirrors a map; treat as failure
            continue
        if c.bijective:
            return UVr, c, r
        if c.flips + c.degenerate + c.wound < (
            best_cert.flips + best_cert.degenerate + best_cert.wound
        ):
            best_UV, best_cert = UVr, c
    return best_UV, best_cert, rounds


def _slim_data(V: np.ndarray, F: np.ndarray, UV0: np.ndarray, b=None, bc=None, energy=None):
    if energy is None:
        energy = igl.MappingEnergyType.SYMMETRIC_DIRICHLET
    fixed = b is not None and len(b) > 0
    return igl.slim_precompute(
        np.asfortranarray(V),
        np.asfortranarray(F.astype(np.int32)),
        np.asfortranarray(UV0),
        energy,
        np.asarray(b if fixed else np.zeros(0), dtype=np.int32),
        np.asfortranarray(bc if fixed else np.zeros((0, 2))),
        SLIM_SOFT_P if fixed else 0.0,
    )


def slim_map(
    V: np.ndarray,
    F: np.ndarray,
    UV0: np.ndarray,
    iterations: int,
    energy=None,
    bnd: np.ndarray | None = None,
) -> np.ndarray:
    """SLIM (libigl) from a flip-free start, no certificate.

    Parameters
    ----------
    V : (n, 3) float64
        Chart vertices.
    F : (m, 3) int64
        Triangles.
    UV0 : (n, 2) float64
        Flip-free start.
    iterations : int
        SLIM iterations.
    energy : igl.MappingEnergyType, optional
        Default: symmetric Dirichlet.
    bnd : (b,) int64, optional
        Vertices held at their start positions (soft constraint, :data:`SLIM_SOFT_P`);
        free boundary when omitted.

    Returns
    -------
    UV : (n, 2) float64

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> UV = slim_map(V, F, np.array([[0.0, 0], [3, 0], [0, 1]]), 5)
    >>> bool(np.allclose(np.linalg.norm(UV[1] - UV[0]), 1, atol=1e-3))
    True
    """
    bc = UV0[bnd] if bnd is not None else None
    data = _slim_data(V, F, UV0, bnd, bc, energy=energy)
    return np.ascontiguousarray(igl.slim_solve(data, iterations)[:, :2])


def slim_guarded(
    V: np.ndarray,
    F: np.ndarray,
    UV0: np.ndarray,
    iterations: int,
    name: str,
    bnd: np.ndarray | None = None,
    loops: list[np.ndarray] | None = None,
    stall: float | None = None,
    give_up: int | None = None,
) -> tuple[np.ndarray, Certificate | None, int, int]:
    """SLIM one iteration at a time from a bijective start; keep the last bijective iterate.

    SLIM's line search prevents flips but not boundary overlaps (free boundary), and an
    overlap can be transient: every iterate is certified and the result is the *last*
    bijective one, the one with the lowest energy (SLIM's energy decreases monotonically).
    Measured on the 20 charts of the shared data set that fall back to Tutte + SLIM, 30
    iterations: 7 have non-bijective iterates; on 5 of them a later iterate is bijective again
    (iron.ply chart 1: iterate 3 overlaps, 4-22 are bijective; stopping at the first
    non-bijective iterate kept iterate 2, symmetric Dirichlet 13.7 instead of 4.01; on
    abc_00007974_5's two charts no iterate before the first overlap was bijective and the
    fixed-boundary variant's 33.4 and 15.7 were kept instead of 4.05 and 4.09).  Certifying
    every iterate costs about a third of an iteration (boundary loops passed in); the
    previous scheme (all iterations, then again one at a time when the result failed) cost
    two SLIM runs whenever an overlap occurred.  With ``bnd`` the boundary is held (soft
    constraint, :data:`SLIM_SOFT_P`) at its start positions.  With ``stall``, SLIM also stops
    at the first bijective iterate whose symmetric Dirichlet energy is less than ``stall``
    times its own value below the previous bijective iterate's (converged; started from a
    Hessian map, SLIM reaches 4.0x within a few iterations).  With ``give_up``, it stops
    after that many non-bijective iterates when none was bijective yet (an optional
    candidate: iron.ply chart 6 ran 30 such iterations, 2.3 s, for nothing).

    Early stop: after :data:`SLIM_STOP_AFTER_BAD` consecutive non-bijective iterates that
    follow a bijective one.  On the 20 fallback charts, once an iterate had been bijective,
    a non-bijective run either lasted one iterate (iron.ply chart 1) or lasted to the last
    iteration (13 iterates on iron chart 7, 20 on block_noisy chart 0), so the stop kept the
    same iterate on all 20 and saved 3-21 of the 30 iterations on 7 of them.

    Returns
    -------
    UV : (n, 2) float64
        Last bijective iterate (``UV0`` when none was).
    cert : Certificate or None
        Its certificate (``None`` when no iterate was bijective).
    accepted : int
        Index (1-based) of the kept iterate, 0 when none.
    bijective_iterates : int
        Number of bijective iterates.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> UV0 = tutte_map(V, F)
    >>> UV, cert, accepted, good = slim_guarded(V, F, UV0, 5, "chart")
    >>> cert.bijective, accepted
    (True, 5)
    """
    bc = UV0[bnd] if bnd is not None else None
    try:
        data = _slim_data(V, F, UV0, bnd, bc)
    except RuntimeError as exc:  # pragma: no cover - libigl failure
        log.warning("%s: SLIM failed: %s", name, exc)
        return UV0, None, 0, 0
    best, best_cert, accepted, good, bad_run = UV0, None, 0, 0, 0
    prev_sd = np.inf
    for it in range(1, iterations + 1):
        try:
            UV = np.ascontiguousarray(igl.slim_solve(data, 1)[:, :2])
        except RuntimeError as exc:  # pragma: no cover - libigl failure
            log.warning("%s: SLIM iteration failed: %s", name, exc)
            break
        if not np.all(np.isfinite(UV)):
            break
        UV, cert = certify_oriented(UV, V, F, name, loops)
        if cert.bijective:
            best, best_cert, accepted, good, bad_run = UV, cert, it, good + 1, 0
            if stall is not None:
                sd = distortion(V, F, UV)["sym_dirichlet"]
                if prev_sd - sd < stall * sd:
                    break
                prev_sd = sd
        else:
            bad_run += 1
            if accepted > 0 and bad_run >= SLIM_STOP_AFTER_BAD:
                break
            if accepted == 0 and give_up is not None and bad_run >= give_up:
                break
    return best, best_cert, accepted, good
