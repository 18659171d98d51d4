"""The package version, read from the installed metadata (the one copy is in pyproject.toml)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

__all__ = ["__version__"]

try:
    __version__ = version("igl_heatseg")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0+unknown"
