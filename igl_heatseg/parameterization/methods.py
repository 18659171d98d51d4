"""One map per method (no fallback), the method registry, and side-by-side comparisons.

:func:`map_chart` maps a disk chart with one of :data:`METHODS`: the Hessian eigenmaps,
the Tutte-based fallbacks run unguarded, and three baselines (harmonic with the boundary on a
circle, LSCM with two boundary vertices pinned, ARAP started from the harmonic map).
:func:`compare_methods` runs several of them, or the full :func:`parameterize_chart`
(:data:`PIPELINE_METHODS`), through the same certificate and distortion code.
"""

from __future__ import annotations

import time
from typing import Iterable, Sequence

import igl
import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from .chart import ChartParam, parameterize_chart
from .distortion import distortion
from .eigenmap import hessian_map
from .fallback import SLIM_ITERATIONS, circle_boundary, slim_map, tutte_map
from .prepare import BLAS_THREADS, certify_oriented, expand_uv, limit_blas_threads, prepare_chart

__all__ = [
    "map_chart",
    "compare_methods",
    "METHODS",
    "PIPELINE_METHODS",
]

#: Full :func:`parameterize_chart` runs (with repair and fallbacks) known to
#: :func:`compare_methods`.
PIPELINE_METHODS: tuple[str, ...] = ("param-hlle", "param-curved", "param-auto")

#: Methods known to :func:`map_chart`.
METHODS: tuple[str, ...] = (
    "hessian-hlle",
    "hessian-curved",
    "tutte",
    "tutte+slim",
    "tutte+slim-fixed",
    "harmonic",
    "lscm",
    "arap",
)


def _harmonic(V, F, bnd):
    return igl.harmonic(V, F, bnd, circle_boundary(V, bnd), 1)


def _lscm(V, F, bnd):
    # Two boundary vertices far apart, fixed at (0,0) and (|p-q|, 0).
    P = V[bnd]
    i = int(np.argmax(((P - P[0]) ** 2).sum(1)))
    j = int(np.argmax(((P - P[i]) ** 2).sum(1)))
    b = np.array([bnd[i], bnd[j]], dtype=np.int64)
    bc = np.array([[0.0, 0.0], [np.linalg.norm(P[i] - P[j]), 0.0]])
    UV, _ = igl.lscm(V, F, b, bc)
    return UV


def _arap(V, F, bnd, iterations=20):
    UV0 = _harmonic(V, F, bnd)
    data = igl.ARAPData()
    data.with_dynamics = True
    data.max_iter = iterations
    igl.arap_precomputation(V, F, 2, np.zeros(0, dtype=np.int32), data)
    return igl.arap_solve(np.zeros((0, 2)), data, UV0)


def _run(method: str, Vn, Fc, bnd, name, energy_kwargs) -> tuple[np.ndarray, np.ndarray | None]:
    lam = None
    if method == "hessian-hlle":
        UVc, lam, _ = hessian_map(Vn, Fc, "hlle", **energy_kwargs)
    elif method == "hessian-curved":
        UVc, lam, _ = hessian_map(Vn, Fc, "curved")
    elif method == "tutte":
        UVc = tutte_map(Vn, Fc, bnd)
    elif method == "tutte+slim":
        UVc = slim_map(Vn, Fc, tutte_map(Vn, Fc, bnd), SLIM_ITERATIONS)
    elif method == "tutte+slim-fixed":
        UVc = slim_map(Vn, Fc, tutte_map(Vn, Fc, bnd), SLIM_ITERATIONS, bnd=bnd)
    elif method == "harmonic":
        UVc = _harmonic(Vn, Fc, bnd)
    elif method == "lscm":
        UVc = _lscm(Vn, Fc, bnd)
    elif method == "arap":
        UVc = _arap(Vn, Fc, bnd)
    else:
        raise MeshError(f"{name}: unknown method {method!r}; known: {', '.join(METHODS)}")
    return np.asarray(UVc, dtype=np.float64), lam


def map_chart(
    V: ArrayLike,
    F: ArrayLike,
    method: str = "hessian-hlle",
    *,
    name: str = "chart",
    **energy_kwargs,
) -> ChartParam:
    """Map a disk chart with one method, no fallback; certify it and measure distortion.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions (vertices not used by ``F`` are allowed and get ``NaN`` UVs).
    F : (m, 3) array_like of int
        Triangles of a topological disk, consistently oriented.
    method : str
        One of :data:`METHODS`.  ``"tutte+slim"`` keeps SLIM's result even if not bijective
        (use :func:`parameterize_chart` for the guarded version).
    name : str
        Chart name for messages.
    **energy_kwargs
        Passed to :func:`~igl_heatseg.parameterization.hessian.hlle_energy` for ``"hessian-hlle"``.

    Returns
    -------
    ChartParam

    Raises
    ------
    MeshError
        Bad arrays, or the chart is not a disk.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> res = map_chart(V, F, "lscm")
    >>> res.method, res.bijective, round(res.distortion["conformal_max"], 9)
    ('lscm', True, 1.0)
    """
    t0 = time.perf_counter()
    V_in = np.asarray(V)
    c = prepare_chart(V, F, name)
    Vn, Fc, used, scale, bnd = c.V, c.F, c.used, c.scale, c.boundary
    try:
        with limit_blas_threads(BLAS_THREADS):
            UVc, lam = _run(method, Vn, Fc, bnd, name, energy_kwargs)
    except RuntimeError as exc:
        raise MeshError(f"{name}: {method} failed in libigl/scipy: {exc}") from None
    if not np.all(np.isfinite(UVc)):
        UVc = np.nan_to_num(UVc, nan=0.0, posinf=0.0, neginf=0.0)
    UVc, cert = certify_oriented(UVc, Vn, Fc, name)
    dist = distortion(Vn, Fc, UVc)
    secs = time.perf_counter() - t0
    return ChartParam(
        UV=expand_uv(UVc / scale, used, V_in.shape[0]),
        method=method,
        bijective=cert.bijective,
        flips=cert.flips,
        overlaps=cert.overlaps,
        distortion=dist,
        seconds=secs,
        eigenvalues=lam,
        certificate=cert,
        attempts=[{"method": method, **cert.summary(), "seconds": secs}],
    )


def compare_methods(
    charts: Iterable[tuple[str, np.ndarray, np.ndarray]],
    methods: Sequence[str] = ("hessian-hlle", "hessian-curved", "harmonic", "lscm"),
) -> list[dict]:
    """Run several parameterization methods on disk charts; one table row per (chart, method).

    Every method goes through the same certificate and distortion code.  Names from
    :data:`METHODS` run :func:`map_chart` (one method, no fallback); ``"param-hlle"``,
    ``"param-curved"``, ``"param-auto"`` run the full :func:`parameterize_chart` (Hessian map,
    repair, certified fallbacks) and report which map it produced.

    Parameters
    ----------
    charts : iterable of (name, V, F)
        Disk charts.
    methods : sequence of str
        Names from :data:`METHODS` or :data:`PIPELINE_METHODS`.

    Returns
    -------
    rows : list of dict
        Keys ``chart, faces, method, bijective, flips, overlaps, degenerate, conformal_mean,
        conformal_max, area_mean, area_max, sym_dirichlet, stretch_max, seconds``; for the
        ``param-*`` names also ``result`` (the method recorded for the chart) and
        ``fallback_used``; ``error`` when a method raised.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> rows = compare_methods([("square", V, F)], ["harmonic", "param-auto"])
    >>> [(r["method"], r["bijective"]) for r in rows]
    [('harmonic', True), ('param-auto', True)]
    """
    rows = []
    for cname, V, F in charts:
        for method in methods:
            row = {"chart": cname, "faces": int(np.shape(F)[0]), "method": method}
            try:
                if method in PIPELINE_METHODS:
                    res = parameterize_chart(V, F, method[len("param-") :], name=str(cname))
                    row.update({"result": res.method, "fallback_used": res.fallback_used})
                else:
                    res = map_chart(V, F, method, name=str(cname))
            except (MeshError, RuntimeError, np.linalg.LinAlgError) as exc:
                row.update({"bijective": False, "error": str(exc)})
                rows.append(row)
                continue
            row.update(
                {
                    "bijective": res.bijective,
                    "flips": res.flips,
                    "overlaps": res.overlaps,
                    "degenerate": res.certificate.degenerate,
                    **res.distortion,
                    "seconds": res.seconds,
                }
            )
            rows.append(row)
    return rows
