"""Draft surface-recovery metrics (to move into ``igl_heatseg.evaluation`` later).

* :func:`type_accuracy`: the share of the area whose predicted segment's surface type equals
  the true (B-Rep) surface type.
* :func:`boundary_length_ratio`: total length of the predicted segment boundaries over the total
  length of the true face boundaries (1 = as much boundary as the CAD model; > 1 over-segmented
  or ragged; < 1 missing boundaries).

Surface kinds are lower case: plane, cylinder, cone, sphere, torus, freeform.  ABC / make_parts
type names map with :func:`kind_of` (Plane -> plane, ..., anything else -> freeform).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "KINDS",
    "kind_of",
    "face_kinds",
    "type_accuracy",
    "boundary_edges",
    "boundary_length",
    "boundary_length_ratio",
]

#: The surface kinds, in a fixed order.
KINDS = ("plane", "cylinder", "cone", "sphere", "torus", "freeform")

_ABC_TO_KIND = {
    "plane": "plane",
    "cylinder": "cylinder",
    "cone": "cone",
    "sphere": "sphere",
    "torus": "torus",
}


def kind_of(name: str | None) -> str:
    """Lower-case surface kind of an ABC / make_parts / fitted type name.

    Parameters
    ----------
    name : str or None
        ``Plane``, ``Cylinder``, ``Cone``, ``Sphere``, ``Torus`` (any case) map to themselves
        in lower case; anything else (BSpline, Extrusion, Revolution, Other, freeform, None)
        is ``freeform``.

    Returns
    -------
    str
    """
    if name is None:
        return "freeform"
    return _ABC_TO_KIND.get(str(name).strip().lower(), "freeform")


def face_kinds(labels: np.ndarray, segment_types) -> np.ndarray:
    """Per-face kinds from per-face labels and one type name per label.

    Parameters
    ----------
    labels : (m,) int
        ``0..k-1``.
    segment_types : sequence of str, length >= k
        Type of every label (any naming :func:`kind_of` accepts).

    Returns
    -------
    (m,) str array

    Raises
    ------
    ValueError
        If a label has no type or is negative.
    """
    labels = np.asarray(labels, dtype=np.int64).reshape(-1)
    kinds = np.array([kind_of(t) for t in segment_types] or ["freeform"], dtype=object)
    if labels.size and (labels.min() < 0 or labels.max() >= len(segment_types)):
        raise ValueError(
            f"labels must be in 0..{len(segment_types) - 1} (one type per label), "
            f"got {labels.min()}..{labels.max()}"
        )
    return kinds[labels].astype(str)


def type_accuracy(pred_types, true_types, weights=None) -> float:
    """Share of the weight (area) whose predicted surface kind equals the true kind.

    Parameters
    ----------
    pred_types, true_types : (m,) sequence of str
        Per-face type names (mapped with :func:`kind_of`, so ABC names and kinds both work).
    weights : (m,) float, optional
        Face areas; ``None`` counts faces.

    Returns
    -------
    float in [0, 1]

    Raises
    ------
    ValueError
        Mismatched lengths, negative weights or zero total weight.
    """
    p = np.array([kind_of(t) for t in pred_types], dtype=object)
    t = np.array([kind_of(x) for x in true_types], dtype=object)
    if p.shape != t.shape:
        raise ValueError(f"pred_types has {p.size} faces, true_types {t.size}")
    w = np.ones(p.size) if weights is None else np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape != p.shape:
        raise ValueError(f"weights has {w.size} entries for {p.size} faces")
    if (w < 0).any():
        raise ValueError("weights must be non-negative")
    total = float(w.sum())
    if total <= 0:
        raise ValueError("type_accuracy: zero total weight")
    return float(w[p == t].sum() / total)


def boundary_edges(F: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Edges between faces of different labels (each once, as vertex pairs).

    Edges with one face (mesh boundary) or more than two faces are not segment boundaries;
    on a non-manifold edge, any two faces of different labels make it a boundary.

    Parameters
    ----------
    F : (m, 3) int
    labels : (m,) int

    Returns
    -------
    (b, 2) int64
        Sorted vertex pairs.
    """
    F = np.asarray(F, dtype=np.int64)
    labels = np.asarray(labels).reshape(-1)
    if labels.shape[0] != F.shape[0]:
        raise ValueError(f"labels has {labels.shape[0]} entries for {F.shape[0]} faces")
    m = len(F)
    if m == 0:
        return np.zeros((0, 2), dtype=np.int64)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    lab = np.tile(labels, 3)
    key = E[:, 0] * (int(F.max()) + 1) + E[:, 1]
    order = np.lexsort((lab, key))
    ks, ls = key[order], lab[order]
    start = np.r_[True, ks[1:] != ks[:-1]]
    group = np.cumsum(start) - 1
    count = np.bincount(group)
    # labels differ within a group iff its first and last (sorted) labels differ
    first = np.flatnonzero(start)
    last = np.r_[first[1:], len(ks)] - 1
    cut = (count >= 2) & (ls[first] != ls[last])
    return E[order[first[cut]]]


def boundary_length(V: np.ndarray, F: np.ndarray, labels: np.ndarray) -> float:
    """Total length of the edges between faces of different labels.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    labels : (m,) int

    Returns
    -------
    float
    """
    E = boundary_edges(F, labels)
    V = np.asarray(V, dtype=np.float64)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).sum())


def boundary_length_ratio(
    V: np.ndarray, F: np.ndarray, pred: np.ndarray, truth: np.ndarray
) -> float:
    """Predicted segment boundary length over true face boundary length.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    pred, truth : (m,) int
        Predicted and true labels.

    Returns
    -------
    float
        ``boundary_length(pred) / boundary_length(truth)``; when the truth has no boundary
        (one face per component), 1.0 if the prediction has none either, else ``inf``.
    """
    bt = boundary_length(V, F, truth)
    bp = boundary_length(V, F, pred)
    if bt == 0:
        return 1.0 if bp == 0 else float("inf")
    return bp / bt
