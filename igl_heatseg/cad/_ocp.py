"""The optional OpenCASCADE dependency (OCP) with an install hint when it is missing."""

from __future__ import annotations

import contextlib

__all__ = ["require_ocp", "quiet_occ"]

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


@contextlib.contextmanager
def quiet_occ():
    """Raise OCC's default message printers to failures only while in the block (the STEP
    translators print transfer statistics on stdout; the package logs instead)."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    saved = []
    for i in range(1, printers.Length() + 1):
        p = printers.Value(i)
        saved.append((p, p.GetTraceLevel()))
        p.SetTraceLevel(Message_Gravity.Message_Fail)
    try:
        yield
    finally:
        for p, level in saved:
            p.SetTraceLevel(level)
