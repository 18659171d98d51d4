"""Which meshes a batch processes, and the output folder of each.

INPUTS are files, folders (searched recursively) and glob patterns (``**`` recursive). A mesh
found under a folder or a pattern keeps its path relative to that folder (or to the pattern's
leading folder): ``parts/a/b.stl`` given as ``parts`` goes to ``OUT/a/b/``. A file given by
name goes to ``OUT/<stem>/``.
"""

from __future__ import annotations

import glob
import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

__all__ = ["MESH_SUFFIXES", "MeshInput", "discover"]

#: File suffixes a folder or a pattern contributes (a file named explicitly is always taken).
MESH_SUFFIXES = (".obj", ".off", ".ply", ".stl")

_GLOB_CHARS = set("*?[")


@dataclass(frozen=True)
class MeshInput:
    """One mesh of a batch.

    Attributes
    ----------
    path : Path
        Absolute path of the file.
    name : str
        Its path relative to the input that found it (POSIX separators): the ``mesh`` column.
    key : str
        Its output folder relative to OUT: ``name`` without the suffix (with it when two
        meshes would share the folder).
    """

    path: Path
    name: str
    key: str


def _is_mesh(p: Path) -> bool:
    return p.is_file() and p.suffix.lower() in MESH_SUFFIXES


def _walk(folder: Path, exclude: Path | None):
    for root, dirs, files in os.walk(folder):
        root_p = Path(root)
        dirs[:] = sorted(
            d
            for d in dirs
            if not d.startswith(".") and (exclude is None or (root_p / d).resolve() != exclude)
        )
        for f in sorted(files):
            p = root_p / f
            if not f.startswith(".") and _is_mesh(p):
                yield p


def _glob_base(pattern: str) -> Path:
    parts = PurePosixPath(pattern.replace(os.sep, "/")).parts
    base = []
    for part in parts:
        if _GLOB_CHARS & set(part):
            break
        base.append(part)
    return Path(*base) if base else Path(".")


def discover(inputs, exclude: str | os.PathLike | None = None) -> list[MeshInput]:
    """The meshes of INPUTS, in input order, each once.

    Parameters
    ----------
    inputs : iterable of str or path-like
        Files, folders and glob patterns.
    exclude : path-like, optional
        A folder never searched (the batch's OUT, when it lies inside an input folder).

    Returns
    -------
    list of MeshInput

    Raises
    ------
    ValueError
        An input that is neither a file, a folder nor a pattern matching a mesh; two meshes
        whose output folders would coincide.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> (root / "sub").mkdir()
    >>> for n in ("a.obj", "sub/b.stl", "notes.txt"):
    ...     _ = (root / n).write_text("")
    >>> [(m.name, m.key) for m in discover([root])]
    [('a.obj', 'a'), ('sub/b.stl', 'sub/b')]
    """
    exclude_p = Path(exclude).resolve() if exclude is not None else None
    found: list[tuple[Path, str]] = []
    for item in inputs:
        text = os.fspath(item)
        p = Path(text)
        if p.is_dir():
            hits = [(f, f.relative_to(p).as_posix()) for f in _walk(p, exclude_p)]
        elif p.is_file():
            hits = [(p, p.name)]
        elif _GLOB_CHARS & set(text):
            base = _glob_base(text)
            hits = []
            for m in sorted(glob.glob(text, recursive=True)):
                mp = Path(m)
                if mp.is_dir():
                    hits += [(f, f.relative_to(base).as_posix()) for f in _walk(mp, exclude_p)]
                elif _is_mesh(mp):
                    hits.append((mp, mp.relative_to(base).as_posix()))
            if not hits:
                raise ValueError(
                    f"{text}: the pattern matches no mesh ({', '.join(MESH_SUFFIXES)})"
                )
        else:
            raise ValueError(f"{text}: no such file or folder")
        if exclude_p is not None:
            hits = [(f, n) for f, n in hits if exclude_p not in f.resolve().parents]
        found += hits
    seen: set[Path] = set()
    unique = []
    for f, name in found:
        r = f.resolve()
        if r not in seen:
            seen.add(r)
            unique.append((r, name))
    stems: dict[str, int] = {}
    for _, name in unique:
        k = str(PurePosixPath(name).with_suffix(""))
        stems[k] = stems.get(k, 0) + 1
    out: list[MeshInput] = []
    keys: dict[str, str] = {}
    for r, name in unique:
        k = str(PurePosixPath(name).with_suffix(""))
        key = name if stems[k] > 1 else k
        if key in keys:
            raise ValueError(
                f"{keys[key]} and {r} would both be written to OUT/{key}/: "
                "run them as separate batches or into separate OUT folders"
            )
        keys[key] = str(r)
        out.append(MeshInput(r, name, key))
    return out
