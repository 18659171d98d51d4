"""The package's exceptions: :class:`MeshError` for bad input, :class:`CutError` for an
internal cutting failure."""

from __future__ import annotations

__all__ = ["MeshError", "CutError"]


class MeshError(ValueError):
    """A mesh (or a file holding one) that the pipeline cannot accept.

    Raised only at the package boundary (file readers, :func:`igl_heatseg.mesh.checks.validate_mesh`
    and public entry points).  The message names the problem and where it is: the file, and
    which faces, edges or vertices, with counts and the first few offenders.

    It subclasses :class:`ValueError`, so ``except ValueError`` also catches it.
    """


class CutError(RuntimeError):
    """Internal failure: the automatic cut did not produce a topological disk.

    Raised by :func:`igl_heatseg.parameterization.cut_to_disk` after it verified its own result; this is a bug (or an input
    the construction does not cover), not bad user input.
    """
