"""The package's one exception type for bad input."""

from __future__ import annotations

__all__ = ["MeshError"]


class MeshError(ValueError):
    """A mesh (or a file holding one) that the pipeline cannot accept.

    Raised only at the package boundary (file readers, :func:`igl_heatseg.checks.validate_mesh`
    and public entry points).  The message names the problem and where it is: the file, and
    which faces, edges or vertices, with counts and the first few offenders.

    It subclasses :class:`ValueError`, so ``except ValueError`` also catches it.
    """
