"""Peer methods for the surface-recovery benchmark (benchmark-only code).

CGAL Efficient RANSAC (Schnabel et al. 2007) through the ``cgal`` Python wheel
(``CGAL.CGAL_Shape_detection.efficient_RANSAC``).  The wheel is GPL: this module is a
benchmark peer only and must never be imported by ``igl_heatseg`` itself.  The xatlas peer
lives in ``igl_heatseg.baselines`` (``xatlas_charts``).

:func:`cgal_ransac` runs on the face centroids with the (outward, unit) face normals, detects
planes, cylinders, cones, spheres and tori with CGAL's default (untuned) parameters, and
returns one label per face and one surface type per label.

Choices (all fixed, none tuned on the benchmark):

* Parameters are CGAL's library defaults (``Efficient_RANSAC::Parameters``): ``min_points``
  = 1 % of the points, ``epsilon`` and ``cluster_epsilon`` = 1 % of the bounding-box diagonal,
  ``normal_threshold`` = 0.9, ``probability`` = 0.01.  The Python wrapper's own default
  ``min_points=1`` is *not* CGAL's default (90 shapes for the 17 B-Rep faces of a 9k-face
  flange, 10x slower), so
  ``min_points`` is passed explicitly.
* Faces whose centroid RANSAC leaves unassigned (``unassigned="grow"``, the default) take the
  label of the nearest assigned face through mesh adjacency (multi-source breadth-first growth
  over edge-adjacent faces, ties to the lowest shape index), and its type.  With
  ``unassigned="own"`` each connected patch of unassigned faces is a segment of type
  ``freeform`` instead.  A mesh component with no assigned face at all is one ``freeform``
  segment.
* A shape's faces may form several mesh-disconnected patches (coplanar faces, coaxial holes,
  the flanks of a gear); each patch becomes its own segment (``split_components=True``, the
  default), as the segments of the heat methods are connected.  Gear, 7.5k faces, 120 B-Rep
  faces: 136 segments, purity 0.88, coverage 0.87 split; 8 segments, purity 0.52 unsplit.
* ``cluster_epsilon`` is CGAL's default unless given; :func:`spacing_cluster_epsilon` derives
  one from the mesh's edge lengths (CGAL's default connects no centroids on coarse meshes and
  then finds next to nothing).  The benchmark table runs both, as ``cgal`` and
  ``cgal-spacing``.
* The shape of each point is read with ``Int_map.get(i)``: the wheel's
  ``Point_set_3.range(int_map)`` does not iterate in point order (85 % of its values differed
  from ``get`` on a 10k-point part).
* Randomness: CGAL draws its samples from ``CGAL::get_default_random()``, seeded once per
  process from the wall clock in seconds; the wrapper exposes no seed, so results vary from
  run to run (and with call order inside a process).  ``seed`` is therefore not accepted;
  repeat runs to see the spread.
* Crashes: ``efficient_RANSAC`` in this wheel sometimes dies with a segmentation fault
  (1 run in 12 on a 1.7k-face cube, depending on the clock seed).  :func:`cgal_ransac_isolated`
  runs the detection in a forked child and retries a crashed run after the clock second has
  changed (so with another seed); the benchmark uses it.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "RansacResult",
    "cgal_available",
    "cgal_ransac",
    "cgal_ransac_isolated",
    "face_adjacency",
    "ransac_type",
    "spacing_cluster_epsilon",
]

#: CGAL's shape names (``Shape::info()``) -> our lower-case surface kinds.
RANSAC_KINDS = {
    "plane": "plane",
    "cylinder": "cylinder",
    "cone": "cone",
    "sphere": "sphere",
    "torus": "torus",
}

#: ``min_points`` default of CGAL's Efficient RANSAC: this fraction of the points.
MIN_POINTS_FRACTION = 0.01

#: :func:`spacing_cluster_epsilon`: this many mean edge lengths (centroids of neighbouring
#: faces are about 0.6 edge lengths apart; 2 leaves room for slivers and irregular meshes).
SPACING_FACTOR = 2.0


@dataclass
class RansacResult:
    """Per-face segmentation by CGAL Efficient RANSAC.

    Attributes
    ----------
    labels : (m,) int64
        Segment of every face, ``0..k-1``.
    types : list of str, length k
        Surface kind of every segment: plane, cylinder, cone, sphere, torus, or freeform
        (faces no shape took, ``unassigned="own"``, or components without any shape).
    unassigned : float
        Fraction of the faces RANSAC left unassigned (before growth).
    shapes : list of str
        CGAL's description of every detected shape (``Shape::info()``).
    seconds : float
        Wall time of the detection (without the point-set construction and post-processing).
    params : dict
        The parameters passed to CGAL.
    crashes : int
        Crashed attempts before this result (:func:`cgal_ransac_isolated`).
    """

    labels: np.ndarray
    types: list
    unassigned: float
    shapes: list
    seconds: float
    params: dict = field(default_factory=dict)
    crashes: int = 0


def cgal_available() -> bool:
    """Whether the ``cgal`` wheel with Efficient RANSAC is importable."""
    try:
        from CGAL.CGAL_Shape_detection import efficient_RANSAC  # noqa: F401
    except ImportError:
        return False
    return True


def ransac_type(info: str) -> str:
    """Surface kind of a CGAL shape description, e.g. ``'Type: plane (..)x - d = 0'``.

    Parameters
    ----------
    info : str

    Returns
    -------
    str
        plane, cylinder, cone, sphere, torus, or freeform if unrecognised.
    """
    head = info.split("Type:", 1)[-1].strip().split()
    return RANSAC_KINDS.get(head[0].lower() if head else "", "freeform")


def face_adjacency(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of faces sharing an edge (manifold edges: exactly two faces).

    Parameters
    ----------
    F : (m, 3) int

    Returns
    -------
    a, b : (p,) int64
        Face ``a[i]`` and face ``b[i]`` share an edge.  Edges with one or more than two faces
        are ignored.
    """
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    key = E[:, 0] * (int(F.max()) + 1) + E[:, 1]
    order = np.argsort(key, kind="stable")
    ks = key[order]
    face = np.tile(np.arange(m, dtype=np.int64), 3)[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    count = np.diff(np.r_[start, len(ks)])
    pair = start[count == 2]
    return face[pair], face[pair + 1]


def _neighbours(m: int, a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    nbr = [[] for _ in range(m)]
    for i, j in zip(a.tolist(), b.tolist(), strict=True):
        nbr[i].append(j)
        nbr[j].append(i)
    return [np.asarray(n, dtype=np.int64) for n in nbr]


def _grow(labels: np.ndarray, nbr: list[np.ndarray]) -> np.ndarray:
    """Multi-source BFS: every ``-1`` face takes the label of its nearest labelled face."""
    out = labels.copy()
    queue = deque(np.flatnonzero(out >= 0).tolist())
    while queue:
        f = queue.popleft()
        for g in nbr[f]:
            if out[g] < 0:
                out[g] = out[f]
                queue.append(g)
    return out


def _components(mask_labels: np.ndarray, nbr: list[np.ndarray]) -> np.ndarray:
    """Split every label into its face-connected pieces; returns new labels ``0..k-1``."""
    m = len(mask_labels)
    comp = np.full(m, -1, dtype=np.int64)
    k = 0
    for s in range(m):
        if comp[s] >= 0:
            continue
        comp[s] = k
        stack = [s]
        while stack:
            f = stack.pop()
            for g in nbr[f]:
                if comp[g] < 0 and mask_labels[g] == mask_labels[f]:
                    comp[g] = k
                    stack.append(g)
        k += 1
    return comp


def spacing_cluster_epsilon(V: np.ndarray, F: np.ndarray) -> float:
    """A ``cluster_epsilon`` from the sampling: the larger of 1 % of the bounding-box diagonal
    and :data:`SPACING_FACTOR` x the mean edge length.

    CGAL keeps of every candidate shape only its largest cluster of points closer than
    ``cluster_epsilon`` to each other.  On face centroids spaced more than 1 % of the diagonal
    apart (most meshes under ~20k faces at ~100 units: mean edges of 1.5-15 units against a
    1.3 epsilon) no two points are "connected", every shape falls under ``min_points`` and
    RANSAC returns little or nothing (a 12 x 12-per-side cube: 96 % unassigned).  This value is
    derived from the mesh only, never tuned on the benchmark.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    mean_edge = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    return max(0.01 * diag, SPACING_FACTOR * mean_edge)


def _face_points(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    P = V[F]
    C = P.mean(axis=1)
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    norm = np.linalg.norm(N, axis=1, keepdims=True)
    N = np.where(norm > 0, N / np.where(norm > 0, norm, 1.0), np.array([0.0, 0.0, 1.0]))
    return C, N


def cgal_ransac(
    V: np.ndarray,
    F: np.ndarray,
    *,
    unassigned: str = "grow",
    split_components: bool = True,
    cluster_epsilon: float | None = None,
) -> RansacResult:
    """Segment a mesh with CGAL Efficient RANSAC on face centroids and normals.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        Consistently oriented triangles (the normals' sign matters to RANSAC).
    unassigned : {"grow", "own"}
        What faces RANSAC leaves unassigned get: the nearest assigned face's label through mesh
        adjacency (default) or one ``freeform`` segment per connected patch.
    split_components : bool
        Split every segment into its face-connected pieces (default); ``False``: one segment
        per shape.
    cluster_epsilon : float, optional
        CGAL's connectivity distance (model units); default CGAL's 1 % of the bounding-box
        diagonal.  See :func:`spacing_cluster_epsilon` for the sampling-based variant.

    Returns
    -------
    RansacResult

    Raises
    ------
    ImportError
        Without the ``cgal`` wheel.
    ValueError
        Bad ``unassigned`` value or an empty mesh.
    """
    import time

    from CGAL.CGAL_Kernel import Point_3, Vector_3
    from CGAL.CGAL_Point_set_3 import Point_set_3
    from CGAL.CGAL_Shape_detection import efficient_RANSAC

    if unassigned not in ("grow", "own"):
        raise ValueError(f"unassigned must be 'grow' or 'own', got {unassigned!r}")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    if m == 0:
        raise ValueError("cgal_ransac: the mesh has no faces")
    C, N = _face_points(V, F)
    ps = Point_set_3()
    ps.add_normal_map()
    for c, n in zip(C.tolist(), N.tolist(), strict=True):
        ps.insert(Point_3(*c), Vector_3(*n))
    shape_map = ps.add_int_map("shape", -1)
    params = dict(
        min_points=max(1, int(MIN_POINTS_FRACTION * m)),
        epsilon=-1.0,  # CGAL: 1 % of the bounding-box diagonal
        cluster_epsilon=-1.0 if cluster_epsilon is None else float(cluster_epsilon),
        normal_threshold=0.9,
        probability=0.01,
    )
    t0 = time.perf_counter()
    infos = list(
        efficient_RANSAC(
            ps,
            shape_map,
            planes=True,
            cones=True,
            cylinders=True,
            spheres=True,
            tori=True,
            **params,
        )
    )
    seconds = time.perf_counter() - t0
    # ``ps.range(shape_map)`` does not iterate in point order in this wheel: read point by point
    raw = np.fromiter((shape_map.get(i) for i in range(m)), dtype=np.int64, count=m)
    shape_types = [ransac_type(s) for s in infos]
    nbr = _neighbours(m, *face_adjacency(F))
    lab = raw.copy()
    types = list(shape_types)
    if unassigned == "grow":
        lab = _grow(lab, nbr)
    # "own" patches, and components that no shape reached: freeform segments
    rest = lab < 0
    if rest.any():
        tmp = np.where(rest, -1, lab)
        comp = _components(tmp, nbr)
        for c in np.unique(comp[rest]):
            lab[comp == c] = len(types)
            types.append("freeform")
    if split_components:
        comp = _components(lab, nbr)
        first = np.zeros(comp.max() + 1, dtype=np.int64)
        first[comp] = np.arange(m)  # any face of each piece
        types = [types[lab[f]] for f in first]
        lab = comp
    # drop unused labels, keep 0..k-1
    used, lab = np.unique(lab, return_inverse=True)
    types = [types[u] for u in used]
    return RansacResult(
        labels=lab.astype(np.int64),
        types=types,
        unassigned=float((raw < 0).mean()),
        shapes=infos,
        seconds=seconds,
        params=params,
    )


def _child(conn, V, F, kwargs) -> None:
    try:
        conn.send(("ok", cgal_ransac(V, F, **kwargs)))
    except Exception as exc:  # reported to the parent, which re-raises
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def cgal_ransac_isolated(
    V: np.ndarray, F: np.ndarray, *, retries: int = 3, timeout: float = 600.0, **kwargs
) -> RansacResult:
    """:func:`cgal_ransac` in a forked child process, retried when CGAL crashes.

    Parameters
    ----------
    V, F : arrays
        The mesh.
    retries : int
        Further attempts after a crash (each waits for the next clock second, so CGAL seeds
        its generator differently).
    timeout : float
        Seconds before a hung child is killed (counted as a crash).
    **kwargs
        Passed to :func:`cgal_ransac`.

    Returns
    -------
    RansacResult
        With ``crashes`` set to the number of failed attempts.

    Raises
    ------
    RuntimeError
        If every attempt crashed, or :func:`cgal_ransac` raised in the child.
    """
    import multiprocessing as mp
    import time

    ctx = mp.get_context("fork")
    crashes = 0
    for _ in range(retries + 1):
        parent, child = ctx.Pipe(duplex=False)
        proc = ctx.Process(target=_child, args=(child, V, F, kwargs))
        proc.start()
        child.close()
        try:  # a crashed child closes the pipe: poll() sees the EOF, recv() raises
            msg = parent.recv() if parent.poll(timeout) else None
        except EOFError:
            msg = None
        proc.join(5.0)
        if proc.is_alive():
            proc.kill()
            proc.join()
        if msg is not None and msg[0] == "ok":
            result = msg[1]
            result.crashes = crashes
            return result
        if msg is not None:
            raise RuntimeError(f"cgal_ransac failed: {msg[1]}")
        crashes += 1
        time.sleep(1.05 - time.time() % 1.0)  # next clock second: another CGAL seed
    raise RuntimeError(f"cgal_ransac crashed {crashes} times (exit code {proc.exitcode})")
