"""The optional OpenCASCADE dependency (OCP) with an install hint when it is missing."""

from __future__ import annotations

__all__ = ["require_ocp"]

INSTALL_HINT = (
    "igl_heatseg.cad needs OpenCASCADE through OCP (cadquery-ocp-novtk 8.0): "
    "pip install 'igl_heatseg[cad]'"
)


def require_ocp() -> None:
    """Raise ImportError with the install hint when OCP cannot be imported."""
    try:
        import OCP  # noqa: F401
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(INSTALL_HINT) from exc
