"""Files in and out: mesh readers (one validated :class:`~igl_heatseg.mesh.CleanMesh` out of
OBJ, OFF, PLY or STL) and result writers (labels, segmented PLY, report JSON, chart and atlas
OBJ). Readers raise only :class:`~igl_heatseg.errors.MeshError`, naming the file and the
problem. Imports ``mesh`` only. A new format goes into ``meshes.py`` (readers) or
``results.py`` (writers).
"""

from .meshes import SUPPORTED_EXTENSIONS, load_mesh, read_mesh_arrays
from .results import (
    atomic_dir,
    is_complete,
    label_colors,
    write_atlas_obj,
    write_boundary_curves,
    write_chart_obj,
    write_labels,
    write_report,
    write_run,
    write_segmentation,
    write_segmented_ply,
)

__all__ = [
    "SUPPORTED_EXTENSIONS",
    "load_mesh",
    "read_mesh_arrays",
    "label_colors",
    "write_labels",
    "write_segmented_ply",
    "write_report",
    "write_segmentation",
    "write_boundary_curves",
    "write_run",
    "write_chart_obj",
    "write_atlas_obj",
    "atomic_dir",
    "is_complete",
]
