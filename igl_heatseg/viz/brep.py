"""The B-Rep picture: the mesh coloured by segment next to the B-Rep's faces coloured by type.

Draws arrays only: the B-Rep's tessellation (triangles, the face of each triangle and the
type of each face) comes from :func:`igl_heatseg.cad.tessellate_by_type`; this module never
imports OpenCASCADE.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .camera import best_view_direction, three_quarter_camera
from .render import screenshot
from .scene import SURFACE_TYPE_COLORS, add_curves, add_mesh, init_polyscope, show_labels

__all__ = ["BREP_PICTURE_SIZE", "brep_type_colors", "face_border_edges", "render_brep"]

log = logging.getLogger(__name__)

#: Width and height of the picture: two views side by side.
BREP_PICTURE_SIZE: tuple[int, int] = (1600, 700)

#: Gap between the mesh and the B-Rep, as a fraction of the mesh's width on screen.
GAP_FRACTION = 0.15

#: OpenCASCADE surface types drawn in the colour of one of :data:`SURFACE_TYPE_COLORS`.
_ALIASES = {"bspline": "freeform", "bezier": "freeform"}

#: Field of view of the orthographic view of both, relative to polyscope's (which sets the
#: orthographic scale): measured to fill the picture with the two views.
ORTHO_ZOOM = 0.66

#: Radius of the B-Rep's face borders, relative to the scene's length scale.
BORDER_RADIUS = 0.0008


def brep_type_colors(face_types) -> np.ndarray:
    """RGB of every face type (B-spline and Bezier faces in the ``freeform`` colour, unknown
    types in ``other``'s).

    Examples
    --------
    >>> brep_type_colors(["plane", "bspline"]).shape
    (2, 3)
    """
    names = [_ALIASES.get(t, t) for t in face_types]
    return np.array([SURFACE_TYPE_COLORS.get(t, SURFACE_TYPE_COLORS["other"]) for t in names],
                    dtype=np.float64).reshape(-1, 3)


def face_border_edges(TF: ArrayLike, tri_face: ArrayLike) -> np.ndarray:
    """Edges of a tessellation whose two triangles lie on different faces, or on one only.

    Examples
    --------
    >>> face_border_edges([[0, 1, 2], [2, 1, 3]], [0, 1]).tolist()
    [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]
    """
    TF = np.asarray(TF, dtype=np.int64).reshape(-1, 3)
    tri_face = np.asarray(tri_face, dtype=np.int64)
    E = np.sort(np.r_[TF[:, [0, 1]], TF[:, [1, 2]], TF[:, [2, 0]]], axis=1)
    owner = np.tile(tri_face, 3)
    pairs = np.unique(np.c_[E, owner], axis=0)  # (edge, face) once each
    edges, counts = np.unique(pairs[:, :2], axis=0, return_counts=True)
    _, uses = np.unique(E, axis=0, return_counts=True)
    return edges[(counts > 1) | (uses == 1)]


def render_brep(
    png: str | os.PathLike,
    V: ArrayLike,
    F: ArrayLike,
    labels: ArrayLike,
    TV: ArrayLike,
    TF: ArrayLike,
    tri_face: ArrayLike,
    face_types,
    size: tuple[int, int] = BREP_PICTURE_SIZE,
    backend: str | None = None,
) -> Path:
    """Write the mesh (left, colours by segment) and the B-Rep (right, colours by face type,
    :data:`~igl_heatseg.viz.scene.SURFACE_TYPE_COLORS`, face borders dark) to one PNG.

    Parameters
    ----------
    png : str or path-like
    V, F : the mesh
    labels : (m,) int
        Segment of every face.
    TV, TF : the B-Rep's tessellation (same coordinates as the mesh)
    tri_face : (q,) int
        Face of every B-Rep triangle, indexing ``face_types``.
    face_types : list of str
        OpenCASCADE type of every face (``plane``, ``cylinder``, ..., ``bspline``).
    size : (width, height)
    backend : str, optional
        polyscope backend (default: headless).

    Returns
    -------
    Path

    Raises
    ------
    ImportError
        polyscope is missing.
    RuntimeError
        No headless OpenGL.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    TV = np.asarray(TV, dtype=np.float64).reshape(-1, 3)
    TF = np.asarray(TF, dtype=np.int64).reshape(-1, 3)
    tri_face = np.asarray(tri_face, dtype=np.int64)
    ps = init_polyscope(backend, headless=True)
    fov = ps.get_vertical_fov_degrees()
    try:
        d = best_view_direction(V, F, labels)
        half = (size[0] / 2, size[1])
        eye, target, up = three_quarter_camera(V, half[0] / half[1],
                                               ps.get_vertical_fov_degrees(), direction=d)
        view = target - eye
        right = np.cross(view, up)
        right /= np.linalg.norm(right)
        width = float(np.ptp(V @ right))
        shift = (1.0 + GAP_FRACTION) * width * right
        show_labels(V, F, labels, "segments", mesh_name="mesh")
        if len(TF):
            m = add_mesh(TV + shift, TF, "brep")
            m.add_color_quantity("face types", brep_type_colors(face_types)[tri_face],
                                 defined_on="faces", enabled=True)
            add_curves(TV + shift, face_border_edges(TF, tri_face), "brep borders",
                       radius=BORDER_RADIUS)
        # the same orthographic view of both
        centre = target + 0.5 * shift
        ps.set_view_projection_mode("orthographic")  # both seen from the same direction
        ps.set_vertical_fov_degrees(ORTHO_ZOOM * fov)
        ps.look_at_dir(centre - view, centre, up)
        screenshot(png, size)
    finally:
        ps.set_view_projection_mode("perspective")
        ps.set_vertical_fov_degrees(fov)
        ps.remove_all_structures()
    log.info("rendered %s", png)
    return Path(png)
