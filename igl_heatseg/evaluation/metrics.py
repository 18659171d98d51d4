"""Comparing a per-face segmentation with ground-truth labels.

Two families of scores, all computed from the area-weighted contingency table of the two
labelings (``N[i, j]`` = area of the faces in predicted segment ``i`` and true segment ``j``):

*Reverse-engineering scores* (higher is better, 1 is perfect):

- **purity** -- share of the area whose predicted segment's majority true segment is its own
  true segment.  Merging two true faces into one segment lowers it; splitting does not.
- **coverage** -- share of the area whose true segment's majority predicted segment is its own
  predicted segment.  Splitting a true face lowers it; merging does not.
- **rand_index** -- area-weighted Rand index: the probability that two surface points drawn
  independently (with replacement) with density proportional to area are classified the same
  way (together / apart) by both labelings.  ``1 - sum a_i^2 - sum b_j^2 + 2 sum p_ij^2`` with
  ``p = N / A``, ``a``, ``b`` its row and column sums.

*Princeton Segmentation Benchmark scores* (Chen, Golovinskiy, Funkhouser, "A Benchmark for
3D Mesh Segmentation", SIGGRAPH 2009).  All are *errors*: lower is better, 0 is perfect.

- **cut discrepancy** ``CD = (DCD(S1=>S2) + DCD(S2=>S1)) / avgRadius``: DCD(S1=>S2) is the mean
  (over the length of the cut edges of S1) geodesic distance to the nearest cut vertex of S2,
  geodesic distance = shortest path along mesh edges (Dijkstra); a cut edge's distance is the
  mean of its two end points' distances.  ``avgRadius`` = area-weighted mean distance of the face
  centroids from the area-weighted centroid of the surface.
- **Hamming distance**: ``Rm = D_H(S1=>S2) / A`` (missing rate, ``= 1 - coverage``),
  ``Rf = D_H(S2=>S1) / A`` (false-alarm rate, ``= 1 - purity``), ``HD = (Rm + Rf) / 2``;
  area-weighted; S1 = prediction, S2 = ground truth.
- **Rand index, PSB convention**: the benchmark reports ``1 - RI`` with RI over *unordered
  pairs of distinct faces*, every face counting once (not area-weighted), exactly the formula
  of the paper.  Our ``psb_rand_index`` is this ``1 - RI``.
- **GCE / LCE** (global / local consistency error, Martin et al. 2001), with faces as points
  weighted by area and region sizes measured in area:
  ``E(S1,S2,f) = |R(S1,f) \\ R(S2,f)| / |R(S1,f)|``,
  ``GCE = min(sum_f w_f E(S1,S2,f), sum_f w_f E(S2,S1,f)) / A``,
  ``LCE = sum_f w_f min(E(S1,S2,f), E(S2,S1,f)) / A``.

Against several human segmentations (PSB), every score is the mean over them, as the benchmark
does.  Label values are plain ids: any integers, not necessarily contiguous; a segment is the set
of faces with one id (connectedness is not required).
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import dijkstra

from ..errors import MeshError
from ..mesh.geometry import face_areas
from ..mesh.topology import edge_topology
from .surfaces import boundary_length, face_kinds, type_accuracy

__all__ = [
    "Evaluation",
    "contingency_table",
    "purity",
    "coverage",
    "rand_index",
    "psb_rand_index",
    "hamming_distance",
    "consistency_errors",
    "cut_edges",
    "directional_cut_discrepancy",
    "mean_radius",
    "cut_discrepancy",
    "evaluate_labels",
    "read_labels",
    "read_truth",
]

logger = logging.getLogger(__name__)

#: Extension of the PSB human segmentation files read from a truth directory.
SEG_SUFFIX = ".seg"

#: A weight total below this (times the largest weight) counts as zero area.
ZERO_AREA_TOL = 1e-300


# --------------------------------------------------------------------------------------------
# Contingency table and the scores that only need it
# --------------------------------------------------------------------------------------------


def _as_labels(labels: ArrayLike, name: str, m: int | None = None) -> np.ndarray:
    try:
        a = np.asarray(labels)
    except Exception as exc:  # ragged input and the like
        raise MeshError(f"{name}: labels must be an array of integers: {exc}") from None
    if a.ndim != 1:
        raise MeshError(f"{name}: labels should have shape (m,), shape is {a.shape}")
    if a.dtype.kind == "f":
        if not (np.all(np.isfinite(a)) and np.all(a == np.round(a))):
            raise MeshError(f"{name}: labels must be integers, found non-integer values")
    elif a.dtype.kind not in "iub":
        raise MeshError(f"{name}: labels must be integers, dtype is {a.dtype}")
    a = a.astype(np.int64)
    if m is not None and a.shape[0] != m:
        raise MeshError(f"{name}: {a.shape[0]} labels for a mesh with {m} faces")
    return a


def contingency_table(
    pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None
) -> np.ndarray:
    """Weighted contingency table of two labelings.

    Parameters
    ----------
    pred : (m,) int
        Predicted label of each face (any integer ids).
    truth : (m,) int
        True label of each face.
    weights : (m,) float, optional
        Weight of each face (its area); ``None`` counts faces.

    Returns
    -------
    N : (kp, kt) float64
        ``N[i, j]`` = total weight of faces with the ``i``-th predicted id and the ``j``-th true
        id (ids in increasing order; only ids that occur).

    Raises
    ------
    MeshError
        If the arrays are not 1-D integer arrays of one length.

    Examples
    --------
    >>> contingency_table([0, 0, 1], [5, 7, 7])
    array([[1., 1.],
           [0., 1.]])
    """
    p = _as_labels(pred, "pred")
    t = _as_labels(truth, "truth", p.shape[0])
    if weights is None:
        w = np.ones(p.shape[0])
    else:
        w = np.asarray(weights, dtype=np.float64)
        if w.shape != p.shape:
            raise MeshError(f"weights: shape {w.shape} does not match {p.shape[0]} labels")
    _, pi = np.unique(p, return_inverse=True)
    _, ti = np.unique(t, return_inverse=True)
    pi, ti = pi.reshape(-1), ti.reshape(-1)
    kp, kt = int(pi.max()) + 1 if len(pi) else 0, int(ti.max()) + 1 if len(ti) else 0
    N = sp.coo_matrix((w, (pi, ti)), shape=(kp, kt)).toarray()
    return N


def _total(N: np.ndarray) -> float:
    A = float(N.sum())
    if A <= ZERO_AREA_TOL:
        raise MeshError("labels: the faces have zero total weight (area)")
    return A


def purity(pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None) -> float:
    """Share of the weight whose predicted segment's majority true segment is its own.

    ``sum_i max_j N[i, j] / A``.  1 when every predicted segment lies in one true segment;
    merging true segments lowers it, splitting them does not.

    Parameters
    ----------
    pred, truth : (m,) int
    weights : (m,) float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    float in (0, 1]
    """
    N = contingency_table(pred, truth, weights)
    return float(N.max(axis=1).sum() / _total(N))


def coverage(pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None) -> float:
    """Share of the weight whose true segment's majority predicted segment is its own.

    ``sum_j max_i N[i, j] / A``.  1 when no true segment is split; splitting lowers it,
    merging does not.

    Parameters
    ----------
    pred, truth : (m,) int
    weights : (m,) float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    float in (0, 1]
    """
    N = contingency_table(pred, truth, weights)
    return float(N.max(axis=0).sum() / _total(N))


def _rand_from_table(N: np.ndarray) -> float:
    P = N / _total(N)
    a, b = P.sum(axis=1), P.sum(axis=0)
    return float(1.0 - (a @ a) - (b @ b) + 2.0 * (P * P).sum())


def rand_index(pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None) -> float:
    """Weighted Rand index (higher is better).

    The probability that two points drawn independently, *with replacement*, with probability
    proportional to ``weights`` (area) are put together by both labelings or apart by both:
    ``1 - sum_i a_i^2 - sum_j b_j^2 + 2 sum_ij p_ij^2`` with ``p = N / A``.

    Parameters
    ----------
    pred, truth : (m,) int
    weights : (m,) float, optional
        Face areas; ``None`` gives every face the same weight.

    Returns
    -------
    float in [0, 1]

    See Also
    --------
    psb_rand_index : the benchmark's face-pair ``1 - RI``.
    """
    return _rand_from_table(contingency_table(pred, truth, weights))


def psb_rand_index(pred: ArrayLike, truth: ArrayLike) -> float:
    """The Princeton benchmark's Rand index *error* ``1 - RI`` (lower is better).

    RI is the share of unordered pairs of distinct faces ``{f, g}`` (every face counts once,
    no area weights) on which the two labelings agree (same segment in both or different
    segments in both), as in Chen et al. 2009, Sec. 4.3.

    Parameters
    ----------
    pred, truth : (m,) int

    Returns
    -------
    float in [0, 1]
        ``0`` for identical labelings (up to renaming); ``0`` for a single face.
    """
    N = contingency_table(pred, truth)
    n = N.sum()
    if n < 2:
        return 0.0

    def pairs(x: np.ndarray) -> float:
        return float((x * (x - 1.0) / 2.0).sum())

    disagree = pairs(N.sum(axis=1)) + pairs(N.sum(axis=0)) - 2.0 * pairs(N)
    return disagree / (n * (n - 1.0) / 2.0)


def hamming_distance(
    pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None
) -> tuple[float, float, float]:
    """PSB Hamming distance with the prediction as S1 and the truth as S2 (lower is better).

    ``D_H(S1=>S2) = sum_j |R2_j \\ R1_best(j)|`` where ``R1_best(j)`` is the predicted segment
    overlapping true segment ``j`` most.

    Parameters
    ----------
    pred, truth : (m,) int
    weights : (m,) float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    Rm : float
        Missing rate ``D_H(S1=>S2) / A`` (``= 1 - coverage``).
    Rf : float
        False-alarm rate ``D_H(S2=>S1) / A`` (``= 1 - purity``).
    HD : float
        ``(Rm + Rf) / 2``.
    """
    N = contingency_table(pred, truth, weights)
    A = _total(N)
    Rm = 1.0 - N.max(axis=0).sum() / A
    Rf = 1.0 - N.max(axis=1).sum() / A
    return float(Rm), float(Rf), float(0.5 * (Rm + Rf))


def consistency_errors(
    pred: ArrayLike, truth: ArrayLike, weights: ArrayLike | None = None
) -> tuple[float, float]:
    """Global and Local Consistency Error (Martin et al. 2001; PSB), lower is better.

    Faces are the points, weighted by ``weights``; region sizes are weight sums.  For a face in
    cell ``(i, j)``: ``E12 = (a_i - N_ij) / a_i``, ``E21 = (b_j - N_ij) / b_j``.

    Parameters
    ----------
    pred, truth : (m,) int
    weights : (m,) float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    GCE : float in [0, 1)
        ``min(sum N_ij E12, sum N_ij E21) / A``: refinements in *one* direction cost nothing.
    LCE : float in [0, 1)
        ``sum N_ij min(E12, E21) / A``: refinements in either direction, face by face, cost
        nothing; ``LCE <= GCE``.
    """
    N = contingency_table(pred, truth, weights)
    A = _total(N)
    a = N.sum(axis=1, keepdims=True)
    b = N.sum(axis=0, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        E12 = np.where(N > 0, (a - N) / a, 0.0)
        E21 = np.where(N > 0, (b - N) / b, 0.0)
    gce = min((N * E12).sum(), (N * E21).sum()) / A
    lce = (N * np.minimum(E12, E21)).sum() / A
    return float(gce), float(lce)


# --------------------------------------------------------------------------------------------
# Cut discrepancy (needs the geometry)
# --------------------------------------------------------------------------------------------


def cut_edges(F: np.ndarray, labels: np.ndarray, topo=None) -> np.ndarray:
    """Interior edges whose two faces carry different labels.

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
    topo : EdgeTopology, optional
        Precomputed :func:`igl_heatseg.mesh.topology.edge_topology` of ``F``.

    Returns
    -------
    (c, 2) int64
        Vertex pairs of the cut edges (boundary edges are never cuts).
    """
    topo = edge_topology(F) if topo is None else topo
    inner = np.flatnonzero(topo.interior)
    ef = topo.EF[inner]
    cut = labels[ef[:, 0]] != labels[ef[:, 1]]
    return topo.E[inner[cut]]


def _edge_graph(V: np.ndarray, E: np.ndarray) -> sp.csr_matrix:
    n = V.shape[0]
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    rows = np.concatenate([E[:, 0], E[:, 1]])
    cols = np.concatenate([E[:, 1], E[:, 0]])
    return sp.csr_matrix((np.concatenate([w, w]), (rows, cols)), shape=(n, n))


def _distance_to(G: sp.csr_matrix, sources: np.ndarray) -> np.ndarray:
    return dijkstra(G, directed=False, indices=np.unique(sources), min_only=True)


def directional_cut_discrepancy(
    V: np.ndarray,
    cuts_from: np.ndarray,
    cuts_to: np.ndarray,
    G: sp.csr_matrix | None = None,
    E: np.ndarray | None = None,
) -> float:
    """DCD(S1=>S2): mean geodesic distance from the cut of S1 to the nearest cut vertex of S2.

    Distances are shortest paths along mesh edges (Dijkstra, Euclidean edge lengths) from the
    vertices of ``cuts_to``; a cut edge of ``cuts_from`` gets the mean of its end points'
    distances, and the mean over edges is weighted by edge length.

    Parameters
    ----------
    V : (n, 3) float64
    cuts_from : (c1, 2) int64
        Cut edges of S1 (see :func:`cut_edges`).
    cuts_to : (c2, 2) int64
        Cut edges of S2.
    G : (n, n) scipy.sparse matrix, optional
        Edge-length graph of the mesh; needed unless ``E`` is given.
    E : (ne, 2) int64, optional
        All mesh edges, to build ``G``.

    Returns
    -------
    float
        ``0`` if S1 has no cut; ``inf`` if S1 has cuts and S2 none (or a cut of S1 lies on a
        component where S2 has none).
    """
    if len(cuts_from) == 0:
        return 0.0
    if len(cuts_to) == 0:
        return math.inf
    if G is None:
        G = _edge_graph(V, E)
    d = _distance_to(G, cuts_to.ravel())
    length = np.linalg.norm(V[cuts_from[:, 0]] - V[cuts_from[:, 1]], axis=1)
    de = 0.5 * (d[cuts_from[:, 0]] + d[cuts_from[:, 1]])
    return float((length * de).sum() / length.sum())


def mean_radius(V: np.ndarray, F: np.ndarray) -> float:
    """PSB's ``avgRadius``: mean distance of the surface from its centroid.

    Area-weighted mean over faces of ``|centroid_f - c|``, with ``c`` the area-weighted mean of
    the face centroids.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    float
    """
    w = face_areas(V, F)
    C = V[F].mean(axis=1)
    c = (w[:, None] * C).sum(axis=0) / w.sum()
    return float((w * np.linalg.norm(C - c, axis=1)).sum() / w.sum())


def cut_discrepancy(V: ArrayLike, F: ArrayLike, pred: ArrayLike, truth: ArrayLike) -> float:
    """PSB Cut Discrepancy ``(DCD(S1=>S2) + DCD(S2=>S1)) / avgRadius`` (lower is better).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    pred, truth : (m,) int
        Face labels of S1 (prediction) and S2 (truth).

    Returns
    -------
    float
        ``0`` when both have no cut; ``inf`` when exactly one has none.

    See Also
    --------
    directional_cut_discrepancy, mean_radius
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    p = _as_labels(pred, "pred", F.shape[0])
    t = _as_labels(truth, "truth", F.shape[0])
    topo = edge_topology(F)
    return _cut_discrepancy(V, F, p, t, topo, _edge_graph(V, topo.E), mean_radius(V, F))


def _cut_discrepancy(V, F, p, t, topo, G, radius) -> float:
    c1, c2 = cut_edges(F, p, topo), cut_edges(F, t, topo)
    d12 = directional_cut_discrepancy(V, c1, c2, G)
    d21 = directional_cut_discrepancy(V, c2, c1, G)
    return float((d12 + d21) / radius)


# --------------------------------------------------------------------------------------------
# All scores at once
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Evaluation:
    """All scores of one predicted labeling against one or several ground truths.

    Every score is the mean over the ground truths.  ``purity``, ``coverage``, ``rand_index``
    are higher-is-better; the PSB scores (``cut_discrepancy``, ``hamming*``,
    ``psb_rand_index`` = 1 - RI, ``gce``, ``lce``) are errors, lower is better.

    Attributes
    ----------
    n_faces : int
    n_segments : int
        Distinct predicted labels.
    n_true_segments : float
        Distinct true labels (mean over the truths).
    n_truths : int
        Number of ground-truth labelings averaged over.
    weighting : str
        ``"area"`` or ``"count"``: the face weights of purity, coverage, rand_index, Hamming,
        GCE and LCE.  ``psb_rand_index`` always counts faces; ``cut_discrepancy`` uses lengths.
    purity, coverage, rand_index : float
    cut_discrepancy : float
    hamming, hamming_rm, hamming_rf : float
    psb_rand_index : float
    gce, lce : float
    boundary_ratio : float
        Predicted over true boundary length (edges between differently labelled faces): 1 when
        the boundaries are right, > 1 staircases and spurious cuts, < 1 missed boundaries
        (:func:`igl_heatseg.evaluation.surfaces.boundary_length_ratio`).
    segment_ratio : float
        ``n_segments`` over the true segment count (mean over the truths).
    type_accuracy : float or None
        Area share whose predicted segment's surface kind equals the true face's kind
        (:func:`igl_heatseg.evaluation.surfaces.type_accuracy`, always area-weighted); ``None``
        unless both the predicted and the true surface types were given.
    per_truth : list of dict
        The same scores for each truth separately.
    """

    n_faces: int
    n_segments: int
    n_true_segments: float
    n_truths: int
    weighting: str
    purity: float
    coverage: float
    rand_index: float
    cut_discrepancy: float
    hamming: float
    hamming_rm: float
    hamming_rf: float
    psb_rand_index: float
    gce: float
    lce: float
    boundary_ratio: float = math.nan
    segment_ratio: float = math.nan
    type_accuracy: float | None = None
    per_truth: list = field(default_factory=list, repr=False)

    def as_dict(self) -> dict:
        """The scores as a plain dict (without ``per_truth``)."""
        d = asdict(self)
        d.pop("per_truth")
        return d


_SCORES = (
    "n_true_segments",
    "purity",
    "coverage",
    "rand_index",
    "cut_discrepancy",
    "hamming",
    "hamming_rm",
    "hamming_rf",
    "psb_rand_index",
    "gce",
    "lce",
    "boundary_ratio",
    "segment_ratio",
)


def evaluate_labels(
    V: ArrayLike,
    F: ArrayLike,
    pred: ArrayLike,
    truths: ArrayLike | Sequence[ArrayLike],
    *,
    weighting: str = "area",
    cut_metric: bool = True,
    pred_types: Sequence[str | None] | None = None,
    truth_types: Sequence[str | None] | None = None,
) -> Evaluation:
    """Score predicted face labels against one or several ground truths.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
        The mesh the labels refer to (labels are in ``F``'s face order).
    pred : (m,) array_like of int
        Predicted face labels.
    truths : (m,) array_like of int, or a sequence of them
        One ground truth, or several (e.g. the PSB human segmentations); scores are averaged.
    weighting : {"area", "count"}
        Face weights for purity, coverage, rand_index, Hamming, GCE, LCE.
    cut_metric : bool
        Compute the cut discrepancy (a Dijkstra per truth; the slowest score).
    pred_types : sequence of str, optional
        Surface type of every predicted label (``pred_types[k]`` for label ``k``; e.g. the
        ``type`` of each entry of robust mode's ``report.json`` ``surfaces``).
    truth_types : sequence of str, optional
        Surface type of every true label (ABC names such as ``Plane`` or kinds; see
        :func:`igl_heatseg.evaluation.surfaces.read_surface_types`).  With ``pred_types``,
        gives ``type_accuracy``; needs a single truth.

    Returns
    -------
    Evaluation

    Raises
    ------
    MeshError
        If a label array's length differs from the face count, labels are not integers,
        ``weighting`` is unknown, a label has no type, or types come with several truths.

    Examples
    --------
    Two triangles of a unit square, one plane predicted where the truth has a plane and a
    cone: half the area is typed right, and the predicted boundary (none) is 0 of the true one.

    >>> ev = evaluate_labels([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                      [[0, 1, 2], [0, 2, 3]], [0, 0], [0, 1],
    ...                      pred_types=["plane"], truth_types=["Plane", "Cone"])
    >>> ev.purity, ev.coverage, ev.type_accuracy, ev.boundary_ratio, ev.segment_ratio
    (0.5, 1.0, 0.5, 0.0, 0.5)
    """
    from ..mesh.checks import as_mesh_arrays

    V, F = as_mesh_arrays(V, F, "mesh")
    m = F.shape[0]
    if m == 0:
        raise MeshError("mesh: no faces to evaluate")
    if weighting not in ("area", "count"):
        raise MeshError(f"weighting must be 'area' or 'count', got {weighting!r}")
    p = _as_labels(pred, "pred", m)
    if isinstance(truths, np.ndarray):
        tlist = [truths] if truths.ndim == 1 else list(truths)
    elif len(truths) and np.ndim(truths[0]) == 0:
        tlist = [truths]  # one labeling given as a plain list of ints
    else:
        tlist = list(truths)
    if not tlist:
        raise MeshError("truth: no ground-truth labelings given")
    tlist = [_as_labels(t, f"truth {k}", m) for k, t in enumerate(tlist)]
    w = face_areas(V, F) if weighting == "area" else None
    typed = pred_types is not None and truth_types is not None
    if typed and len(tlist) != 1:
        raise MeshError(f"surface types: need a single truth, got {len(tlist)} labelings")

    topo = edge_topology(F)
    if cut_metric:
        G = _edge_graph(V, topo.E)
        radius = mean_radius(V, F)
    bp = boundary_length(V, F, p, topo)
    kp = len(np.unique(p))
    per = []
    for t in tlist:
        bt = boundary_length(V, F, t, topo)
        bratio = (bp / bt) if bt > 0 else (1.0 if bp == 0 else math.inf)
        rm, rf, hd = hamming_distance(p, t, w)
        gce, lce = consistency_errors(p, t, w)
        per.append(
            dict(
                n_true_segments=float(len(np.unique(t))),
                purity=purity(p, t, w),
                coverage=coverage(p, t, w),
                rand_index=rand_index(p, t, w),
                cut_discrepancy=(
                    _cut_discrepancy(V, F, p, t, topo, G, radius) if cut_metric else math.nan
                ),
                hamming=hd,
                hamming_rm=rm,
                hamming_rf=rf,
                psb_rand_index=psb_rand_index(p, t),
                gce=gce,
                lce=lce,
                boundary_ratio=bratio,
                segment_ratio=kp / len(np.unique(t)),
            )
        )
    mean = {k: float(np.mean([d[k] for d in per])) for k in _SCORES}
    if typed:
        acc = type_accuracy(
            face_kinds(p, pred_types), face_kinds(tlist[0], truth_types), face_areas(V, F)
        )
        per[0]["type_accuracy"] = mean["type_accuracy"] = acc
    return Evaluation(
        n_faces=m,
        n_segments=int(len(np.unique(p))),
        n_truths=len(tlist),
        weighting=weighting,
        per_truth=per,
        **mean,
    )


# --------------------------------------------------------------------------------------------
# Readers
# --------------------------------------------------------------------------------------------


def read_labels(path: str | os.PathLike, n_faces: int | None = None) -> np.ndarray:
    """Read face labels: one integer per line (PSB ``.seg``, ABC ``facelabels.txt``, ours).

    Blank lines and lines starting with ``#`` are skipped.

    Parameters
    ----------
    path : path-like
    n_faces : int, optional
        Expected number of labels (the mesh's face count).

    Returns
    -------
    (m,) int64

    Raises
    ------
    MeshError
        If the file cannot be read, a line is not an integer, or the count differs from
        ``n_faces``.
    """
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise MeshError(f"{path}: cannot read labels: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise MeshError(f"{path}: not a text file of integer labels") from None
    out = []
    for k, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        try:
            out.append(int(s.split()[0]))
        except ValueError:
            raise MeshError(f"{path}: line {k} is not an integer label: {s[:40]!r}") from None
    labels = np.asarray(out, dtype=np.int64)
    if n_faces is not None and labels.shape[0] != n_faces:
        raise MeshError(
            f"{path}: {labels.shape[0]} labels for a mesh with {n_faces} faces "
            "(one label per face, in the mesh file's face order)"
        )
    return labels


def read_truth(path: str | os.PathLike, n_faces: int | None = None) -> list[np.ndarray]:
    """Read one ground truth (a label file) or several (a directory of ``.seg`` files).

    Parameters
    ----------
    path : path-like
        A label file, or a directory; from a directory every ``*.seg`` file is read, in
        natural order of the numbers in their names (``324_2.seg`` before ``324_10.seg``).
    n_faces : int, optional
        Expected label count of every file.

    Returns
    -------
    list of (m,) int64

    Raises
    ------
    MeshError
        If the path does not exist, a directory holds no ``.seg`` file, or a file is bad.
    """
    path = Path(path)
    if path.is_dir():
        files = sorted(path.glob("*" + SEG_SUFFIX), key=_natural_key)
        if not files:
            raise MeshError(f"{path}: directory holds no {SEG_SUFFIX} files")
        return [read_labels(f, n_faces) for f in files]
    if not path.exists():
        raise MeshError(f"{path}: no such file or directory")
    return [read_labels(path, n_faces)]


def _natural_key(p: Path):
    import re

    return [int(s) if s.isdigit() else s for s in re.split(r"(\d+)", p.name)]


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------
