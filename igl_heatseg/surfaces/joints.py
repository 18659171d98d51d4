"""Tangent pipe joints: the boundary of a cylinder and the torus or sphere it runs into.

A pipe's straight cylinder runs tangentially into its bend's torus (the cylinder's axis is a
tangent of the torus's centre circle and the radii are equal), and a hemispherical end into its
cylinder (the sphere's centre on the axis, the radii equal). Within the noise of the joint the
faces lie on both surfaces: face-by-face moves and the minimum cut of
:mod:`~igl_heatseg.surfaces.boundary_cut` leave the border up to a few tube radii off it (the
generated pipe elbows: 3-8 % of each cylinder's area on the wrong side). The joint itself is
known from the two fitted surfaces: the plane through the tangent point (the foot of the
torus's or sphere's centre on the cylinder's axis) square to the axis. The faces of the two
segments near it take the label of their side (:func:`tangent_joints`), chosen together by a
minimum cut (:func:`~igl_heatseg.surfaces.boundary_cut.binary_min_cut`) that weighs each face's
distance beyond the plane (in mean edge lengths) against the border's length: the fitted plane
is a fraction of an edge off (the torus of a noisy bend: 0.9 units of 2.4 on a generated
elbow), and cutting the faces by their centroids then leaves a staircase across the triangles
(1.3 times the joint's length) where the mesh has a loop of edges on the joint.
"""
from __future__ import annotations

import igl
import numpy as np

from ..mesh.geometry import face_areas
from ..mesh.topology import label_pieces
from .boundary_cut import CAP, SMOOTHNESS, binary_min_cut

__all__ = ["tangent_joints", "JOINT_REL_TOL", "JOINT_NOISE_TOL", "JOINT_AXIS_COS", "JOINT_REACH"]

#: Two fitted surfaces meet tangentially when their radii, and the distance of the torus's
#: centre from the cylinder's axis and its major radius (0 for a sphere), agree within
#: JOINT_NOISE_TOL x noise or JOINT_REL_TOL x the radius, whichever is larger (a dome of radius
#: 25.7 on a cylinder of radius 24.7 meets it at a crease, which the moves find).
JOINT_REL_TOL = 0.01
JOINT_NOISE_TOL = 2.0

#: ... and the torus's axis is square to the cylinder's (|cos| at most this): the cylinder's
#: axis lies in the bend's plane.
JOINT_AXIS_COS = 0.05

#: Faces within this many tube radii of the tangent point may change sides.
JOINT_REACH = 2.0


def _pairs(labels, TT):
    nl = np.where(TT >= 0, labels[np.maximum(TT, 0)], -1)
    m = (nl >= 0) & (nl != labels[:, None])
    a, b = np.broadcast_to(labels[:, None], nl.shape)[m], nl[m]
    return sorted({(int(min(x, y)), int(max(x, y))) for x, y in zip(a, b, strict=True)})


def _joint(s_cyl, s_other, noise):
    """Tangent point and unit axis of a tangent joint, or None."""
    p0, r = s_cyl.params["point"], s_cyl.params["radius"]
    d = s_cyl.params["axis"] / np.linalg.norm(s_cyl.params["axis"])
    if s_other.kind == "torus":
        c, R, rr = (s_other.params[k] for k in ("center", "major_radius", "minor_radius"))
        ax = s_other.params["axis"] / np.linalg.norm(s_other.params["axis"])
        if abs(float(ax @ d)) > JOINT_AXIS_COS:
            return None
    else:
        c, R, rr = s_other.params["center"], 0.0, s_other.params["radius"]
    P = p0 + float((c - p0) @ d) * d
    slack = max(JOINT_NOISE_TOL * noise, JOINT_REL_TOL * r)
    if abs(rr - r) > slack or abs(float(np.linalg.norm(c - P)) - R) > max(slack, JOINT_REL_TOL * R):
        return None
    return P, d, r


def tangent_joints(V, F, labels, fits: dict, TT, noise: float) -> int:
    """Put the border of every tangent cylinder-torus and cylinder-sphere pair on its joint.

    For each pair of adjacent segments, a cylinder and a torus (or sphere) that meet
    tangentially (see :data:`JOINT_REL_TOL`), the faces of the two within JOINT_REACH tube
    radii of the tangent point ``P`` are labelled together by the minimum of::

        E = sum_f area_f * min((s_f / h)^2, CAP) [f on the wrong side] + SMOOTHNESS * h * |border|

    with ``s_f`` the distance of face ``f``'s centroid from the plane through ``P`` square to
    the cylinder's axis (the cylinder's side is the side of its faces), ``h`` the mean edge
    length and the faces beyond the reach fixed (the constants of
    :mod:`~igl_heatseg.surfaces.boundary_cut`). A piece that this cuts off its segment goes back
    to the segment around it.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment per face; changed in place.
    fits : dict
        Segment id -> Surface (fitted; not refitted here).
    TT : (m, 3) int64
        Triangle-triangle adjacency (-1 on the border).
    noise : float
        Noise level (model units).

    Returns
    -------
    int
        Faces moved.

    Examples
    --------
    A noisy tube (radius 3) running from a cylinder into a torus bend (major radius 10) at arc
    length 0, segmented with the border 2 units into the bend:

    >>> import igl, numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> s, phi = np.meshgrid(np.arange(-12, 15.6, 0.4), np.arange(0, 2 * np.pi, 0.13),
    ...                      indexing="ij")
    >>> t = np.clip(s, 0, None) / 10
    >>> ring = np.cos(phi)[..., None] * np.stack([-np.sin(t), 0 * t, np.cos(t)], -1)
    >>> ring[..., 1] += np.sin(phi)
    >>> spine = np.stack([np.where(s < 0, s, 10 * np.sin(t)), 0 * s,
    ...                   np.where(s < 0, 0, 10 - 10 * np.cos(t))], -1)
    >>> V = (spine + 3 * ring).reshape(-1, 3)
    >>> V += np.random.default_rng(0).normal(0, 0.05, V.shape)
    >>> i = np.arange(s.size).reshape(s.shape)
    >>> a, b = i[:-1].ravel(), i[1:].ravel()
    >>> c, d = np.roll(i[1:], -1, 1).ravel(), np.roll(i[:-1], -1, 1).ravel()
    >>> F = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    >>> arc = s.ravel()[F].mean(axis=1)
    >>> labels = (arc > 2).astype(np.int64)
    >>> fits = {0: Surface("cylinder", {"point": np.zeros(3), "axis": np.array([1.0, 0, 0]),
    ...                                 "radius": 3.0}),
    ...         1: Surface("torus", {"center": np.array([0.0, 0, 10]),
    ...                              "axis": np.array([0.0, 1, 0]), "major_radius": 10.0,
    ...                              "minor_radius": 3.0})}
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> tangent_joints(V, F, labels, fits, TT, 0.05) > 0
    True
    >>> bool((labels == (arc > 0)).all())
    True
    """
    C = V[F].mean(axis=1)
    area = face_areas(V, F)
    h = float(igl.avg_edge_length(V, F))
    moved = 0
    for a, b in _pairs(labels, TT):
        if fits[b].kind == "cylinder":
            a, b = b, a
        if fits[a].kind != "cylinder" or fits[b].kind not in ("torus", "sphere"):
            continue
        joint = _joint(fits[a], fits[b], noise)
        if joint is None:
            continue
        P, d, r = joint
        fa = np.flatnonzero(labels == a)
        side = float(np.sign(np.mean((C[fa] - P) @ d)))
        both = np.r_[fa, np.flatnonzero(labels == b)]
        if not side:
            continue
        near = both[np.linalg.norm(C[both] - P, axis=1) <= JOINT_REACH * r]
        old = labels[both].copy()
        labels[near] = _cut(V, F, TT, labels, near, (C[near] - P) @ d * side, area, h, a, b)
        # a piece cut off its segment goes back to the segment around it
        sub = np.full(len(F), -1, dtype=np.int64)
        sub[both] = labels[both]
        piece = label_pieces(F, sub, TT)[both]
        for k in (a, b):
            ids, counts = np.unique(piece[labels[both] == k], return_counts=True)
            for p in ids[counts < counts.max()]:
                labels[both[piece == p]] = b if k == a else a
        moved += int((labels[both] != old).sum())
    return moved


def _cut(V, F, TT, labels, near, s, area, h, a, b):
    """Labels ``a``/``b`` of the faces ``near`` (signed distances ``s`` from the joint's plane,
    positive on ``a``'s side) by the minimum cut of :func:`tangent_joints`."""
    wrong = area[near] * np.minimum((s / h) ** 2, CAP)
    cost_a, cost_b = np.where(s < 0, wrong, 0.0), np.where(s > 0, wrong, 0.0)
    index = np.full(len(F), -1, dtype=np.int64)
    index[near] = np.arange(len(near))
    f = np.repeat(near, 3)
    g = TT[near].ravel()
    k = np.tile(np.arange(3), len(near))
    length = np.linalg.norm(V[F[f, k]] - V[F[f, (k + 1) % 3]], axis=1)
    w = SMOOTHNESS * h * length
    inner = (g >= 0) & (index[np.maximum(g, 0)] >= 0)
    once = inner & (f < g)
    # a neighbour beyond the reach keeps its label: differing from it costs the edge
    outer = (g >= 0) & ~inner & np.isin(labels[np.maximum(g, 0)], (a, b))
    fo, lo = index[f[outer]], labels[g[outer]]
    cost_a += np.bincount(fo, w[outer] * (lo != a), len(near))
    cost_b += np.bincount(fo, w[outer] * (lo != b), len(near))
    to_b = binary_min_cut(cost_a, cost_b, index[f[once]], index[g[once]], w[once])
    return np.where(to_b, b, a)
