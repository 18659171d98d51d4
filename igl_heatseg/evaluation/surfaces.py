"""Surface-recovery scores: surface types, boundary length and segment count against a B-Rep.

A segment recovered for reverse engineering should be one face of the part's CAD model, of the
right surface type, with its boundary where the neighbouring face begins.  Three scores beside
purity and coverage (:mod:`igl_heatseg.evaluation.metrics`) measure that:

- **type accuracy** (:func:`type_accuracy`) -- share of the area (the weights) whose predicted
  segment's surface kind equals the true face's kind.  Kinds are the fitted-surface kinds of
  :data:`igl_heatseg.surfaces.SURFACE_KINDS`: ``plane``, ``cylinder``, ``cone``, ``sphere``,
  ``torus``, ``freeform``; ground-truth (ABC, ``tools/make_parts.py``) names map with
  :func:`surface_kind` (``Plane`` -> ``plane``, ..., ``BSpline``/``Revolution``/anything else
  -> ``freeform``).
- **boundary length ratio** (:func:`boundary_length_ratio`) -- total length of the mesh edges
  between differently labelled faces, predicted over true: 1 when the boundaries are right,
  above 1 for staircases (zig-zag rims) and spurious cuts, below 1 for missed boundaries.  Only
  edges with exactly two faces count (a mesh border or a non-manifold edge is no boundary
  between two segments).
- **segment ratio** (:func:`segment_ratio`) -- predicted segments over true faces.

Per-face kinds come from per-segment types with :func:`face_kinds`; true per-segment types are
read from ``*.surface_types.txt`` files (``k Type`` per line) with :func:`read_surface_types`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..mesh.topology import edge_topology
from ..surfaces import SURFACE_KINDS

__all__ = [
    "SURFACE_KINDS",
    "surface_kind",
    "face_kinds",
    "read_surface_types",
    "type_accuracy",
    "boundary_length",
    "boundary_length_ratio",
    "segment_ratio",
]

#: Suffix of the true surface-type files beside a part's ``NAME.facelabels.txt``.
SURFACE_TYPES_SUFFIX = ".surface_types.txt"

#: Lower-case names that are a kind of their own; every other name is ``freeform``.
_NAMED_KINDS = {k: k for k in SURFACE_KINDS if k != "freeform"}


def surface_kind(name: str | None) -> str:
    """Surface kind of a type name (ABC, ``make_parts``, fitted or peer).

    Parameters
    ----------
    name : str or None
        ``Plane``, ``Cylinder``, ``Cone``, ``Sphere``, ``Torus`` (any case, surrounding blanks
        ignored) map to themselves in lower case; anything else (``BSpline``, ``Revolution``,
        ``Extrusion``, ``Other``, ``freeform``, ``None``) is ``freeform``.

    Returns
    -------
    str
        One of :data:`SURFACE_KINDS`.

    Examples
    --------
    >>> surface_kind("Cylinder"), surface_kind("torus"), surface_kind("BSpline")
    ('cylinder', 'torus', 'freeform')
    """
    if name is None:
        return "freeform"
    return _NAMED_KINDS.get(str(name).strip().lower(), "freeform")


def face_kinds(labels: ArrayLike, segment_types: Sequence[str | None]) -> np.ndarray:
    """Per-face surface kinds from per-face labels and one type name per label.

    Parameters
    ----------
    labels : (m,) array_like of int
        Segment of every face; a label ``k`` takes ``segment_types[k]``.
    segment_types : sequence of str or None
        Type of every label, any name :func:`surface_kind` accepts.

    Returns
    -------
    (m,) ndarray of str

    Raises
    ------
    MeshError
        If a label is negative or has no type.

    Examples
    --------
    >>> face_kinds([1, 0, 1], ["Plane", "BSpline"]).tolist()
    ['freeform', 'plane', 'freeform']
    """
    lab = np.asarray(labels).reshape(-1).astype(np.int64)
    kinds = np.array([surface_kind(t) for t in segment_types] + ["freeform"], dtype=object)
    if lab.size and (lab.min() < 0 or lab.max() >= len(segment_types)):
        raise MeshError(
            f"surface types: labels run {lab.min()}..{lab.max()} but {len(segment_types)} "
            "types are given (one type per label 0..k-1)"
        )
    return kinds[lab].astype(str)


def read_surface_types(path: str | os.PathLike, n_labels: int | None = None) -> list[str]:
    """Read a ``*.surface_types.txt`` file: ``k Type`` per line (ABC, ``make_parts``).

    Blank lines and lines starting with ``#`` are skipped; lines may come in any order, but the
    ids must be ``0..k-1``, each once.  The type is the rest of the line after the id.

    Parameters
    ----------
    path : path-like
    n_labels : int, optional
        Labels the types must cover (the true labels' largest id + 1); more types are allowed.

    Returns
    -------
    list of str
        ``types[k]`` is the type name of label ``k`` (as written; map with
        :func:`surface_kind`).

    Raises
    ------
    MeshError
        If the file cannot be read, a line is malformed, an id repeats or is missing, or fewer
        than ``n_labels`` types are given.
    """
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise MeshError(f"{path}: cannot read surface types: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise MeshError(f"{path}: not a text file of surface types") from None
    types: dict[int, str] = {}
    for n, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = s.split(None, 1)
        try:
            k = int(parts[0])
        except ValueError:
            k = -1
        if k < 0 or len(parts) < 2:
            raise MeshError(f"{path}: line {n} is not 'id Type': {s[:40]!r}")
        if k in types:
            raise MeshError(f"{path}: line {n}: id {k} appears twice")
        types[k] = parts[1].strip()
    missing = sorted(set(range(len(types))) - set(types))
    if missing:
        raise MeshError(f"{path}: ids must be 0..{len(types) - 1}; missing {missing[:5]}")
    if n_labels is not None and len(types) < n_labels:
        raise MeshError(f"{path}: {len(types)} surface types for {n_labels} labels")
    return [types[k] for k in range(len(types))]


def type_accuracy(
    pred_kinds_per_face: Sequence[str | None],
    true_kinds_per_face: Sequence[str | None],
    weights: ArrayLike | None = None,
) -> float:
    """Share of the weight (area) whose predicted surface kind equals the true kind.

    Parameters
    ----------
    pred_kinds_per_face, true_kinds_per_face : (m,) sequence of str
        Kind of every face's predicted segment and of its true face (any names
        :func:`surface_kind` accepts, so ABC names and kinds compare equal).
    weights : (m,) array_like of float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    float in [0, 1]

    Raises
    ------
    MeshError
        If the lengths differ, a weight is negative, or the total weight is zero.

    Examples
    --------
    >>> type_accuracy(["plane", "cone", "plane"], ["Plane", "Torus", "Plane"], [1.0, 2.0, 1.0])
    0.5
    """
    p = np.array([surface_kind(k) for k in pred_kinds_per_face], dtype=object)
    t = np.array([surface_kind(k) for k in true_kinds_per_face], dtype=object)
    if p.shape != t.shape:
        raise MeshError(f"type accuracy: {p.size} predicted kinds for {t.size} true kinds")
    if weights is None:
        w = np.ones(p.size)
    else:
        w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape != p.shape:
        raise MeshError(f"type accuracy: {w.size} weights for {p.size} faces")
    if (w < 0).any():
        raise MeshError("type accuracy: weights must be non-negative")
    total = float(w.sum())
    if not total > 0:
        raise MeshError("type accuracy: the faces have zero total weight (area)")
    return float(w[p == t].sum() / total)


def _boundary_length(V: np.ndarray, F: np.ndarray, labels: np.ndarray, topo) -> float:
    inner = np.flatnonzero(topo.interior)
    ef = topo.EF[inner]
    E = topo.E[inner[labels[ef[:, 0]] != labels[ef[:, 1]]]]
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).sum())


def _check(V, F, labels, name):
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    lab = np.asarray(labels).reshape(-1)
    if lab.shape[0] != F.shape[0]:
        raise MeshError(f"{name}: {lab.shape[0]} labels for a mesh with {F.shape[0]} faces")
    return V, F, lab


def boundary_length(V: ArrayLike, F: ArrayLike, labels: ArrayLike, topo=None) -> float:
    """Total length of the edges between two faces of different labels.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    labels : (m,) array_like of int
    topo : EdgeTopology, optional
        Precomputed :func:`igl_heatseg.mesh.topology.edge_topology` of ``F``.

    Returns
    -------
    float
        Sum over edges with exactly two faces whose labels differ.

    Examples
    --------
    Two triangles of a unit square, labelled apart: the boundary is the diagonal.

    >>> V = [[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> round(boundary_length(V, [[0, 1, 2], [0, 2, 3]], [0, 1]), 6)
    1.414214
    """
    V, F, lab = _check(V, F, labels, "labels")
    topo = edge_topology(F) if topo is None else topo
    return _boundary_length(V, F, lab, topo)


def boundary_length_ratio(
    V: ArrayLike, F: ArrayLike, pred: ArrayLike, truth: ArrayLike, topo=None
) -> float:
    """Predicted boundary length over true boundary length.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    pred, truth : (m,) array_like of int
        Predicted and true face labels (any integer ids).
    topo : EdgeTopology, optional
        Precomputed :func:`igl_heatseg.mesh.topology.edge_topology` of ``F``.

    Returns
    -------
    float
        ``boundary_length(pred) / boundary_length(truth)``: 1 when the boundaries are right,
        > 1 for staircases and spurious cuts, < 1 for missed boundaries.  When the truth has no
        boundary: 1.0 if the prediction has none either, else ``inf``.

    Examples
    --------
    A strip of four triangles cut in the middle (the truth) and at every edge (over-cut):

    >>> V = [[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]]
    >>> F = [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]
    >>> boundary_length_ratio(V, F, [0, 0, 1, 1], [0, 0, 1, 1])
    1.0
    >>> round(boundary_length_ratio(V, F, [0, 1, 2, 3], [0, 0, 1, 1]), 4)
    3.8284
    """
    V, F, p = _check(V, F, pred, "pred")
    _, _, t = _check(V, F, truth, "truth")
    topo = edge_topology(F) if topo is None else topo
    bt = _boundary_length(V, F, t, topo)
    bp = _boundary_length(V, F, p, topo)
    if bt == 0:
        return 1.0 if bp == 0 else math.inf
    return bp / bt


def segment_ratio(pred: ArrayLike, truth: ArrayLike) -> float:
    """Number of predicted segments over number of true faces (distinct labels each).

    Parameters
    ----------
    pred, truth : (m,) array_like of int

    Returns
    -------
    float

    Examples
    --------
    >>> segment_ratio([0, 1, 2, 2], [7, 7, 9, 9])
    1.5
    """
    kp = np.unique(np.asarray(pred).reshape(-1)).size
    kt = np.unique(np.asarray(truth).reshape(-1)).size
    if kt == 0:
        raise MeshError("segment ratio: no true labels")
    return kp / kt
