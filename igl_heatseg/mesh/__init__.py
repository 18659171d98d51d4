"""The mesh boundary and mesh primitives.

Contract: :func:`validate_mesh` is the one place a mesh enters the package; it returns a frozen
:class:`CleanMesh` (``V (n,3) float64``, ``F (m,3) int64``, C-contiguous, with the map back to
the input's vertex order), or raises :class:`~igl_heatseg.errors.MeshError` naming the problem
and where; with ``repair=True`` it repairs what real exports get wrong instead
(:mod:`.repair`). Everything downstream trusts a ``CleanMesh``. ``topology`` (edges, fans, components,
boundary loops) and ``geometry`` (areas, normals, dihedral angles, on libigl's own routines)
are the one home of mesh primitives. Imports nothing above ``errors``/``constants``.
"""

from .checks import CleanMesh, as_mesh_arrays, validate_mesh
from .geometry import face_areas, face_normals, uv_areas
from .repair import RepairResult, repair_mesh

__all__ = [
    "CleanMesh",
    "validate_mesh",
    "as_mesh_arrays",
    "repair_mesh",
    "RepairResult",
    "face_areas",
    "face_normals",
    "uv_areas",
]
