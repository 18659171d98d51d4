"""Mesh readers: OBJ, OFF, PLY and STL files in, a validated :class:`CleanMesh` out.

The readers are our own, not libigl's: libigl's readers accept bad files silently (an OFF
header declaring 99,999,999 vertices in a 30-byte file hangs ``igl.read_triangle_mesh``; an
empty file returns empty arrays).  Every reader checks what the file declares against what it
holds and raises :class:`~igl_heatseg.MeshError` naming the file and the problem.

Supported: OBJ, OFF, PLY (ascii, binary little/big endian), STL (ascii, binary).  Faces must
be triangles.  STL stores three vertices per face; they are merged by
:func:`igl_heatseg.mesh.checks.validate_mesh`, which :func:`load_mesh` calls.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..mesh.checks import CleanMesh, validate_mesh

__all__ = ["SUPPORTED_EXTENSIONS", "read_mesh_arrays", "load_mesh"]

SUPPORTED_EXTENSIONS = (".obj", ".off", ".ply", ".stl")


def load_mesh(path: str | os.PathLike) -> CleanMesh:
    """Read a triangle mesh file and validate it.

    Parameters
    ----------
    path : str or path-like
        ``.obj``, ``.off``, ``.ply`` or ``.stl`` file.

    Returns
    -------
    CleanMesh
        Validated mesh; ``F`` in the file's face order, ``vertex_map`` from the file's vertex
        numbering to the cleaned one.

    Raises
    ------
    MeshError
        Missing or unreadable file, unknown extension, malformed content, or a mesh that
        :func:`~igl_heatseg.mesh.checks.validate_mesh` rejects.
    """
    V, F = read_mesh_arrays(path)
    return validate_mesh(V, F, name=Path(path).name)


def read_mesh_arrays(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read vertex and face arrays from a mesh file, without validating the mesh.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
        0-based, as stored (not range-checked: see :func:`load_mesh`).

    Raises
    ------
    MeshError
    """
    p = Path(path)
    name = p.name
    ext = p.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise MeshError(
            f"{name}: unknown mesh file extension {ext or '(none)'!r}; "
            f"supported: {', '.join(SUPPORTED_EXTENSIONS)}"
        )
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise MeshError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise MeshError(f"{p}: is a directory, not a mesh file") from None
    except OSError as exc:
        raise MeshError(f"{p}: cannot read file: {exc.strerror or exc}") from None
    if len(data.strip()) == 0:
        raise MeshError(f"{name}: empty file")
    reader = {".obj": _read_obj, ".off": _read_off, ".ply": _read_ply, ".stl": _read_stl}[ext]
    V, F = reader(data, name)
    if F.shape[0] == 0:
        raise MeshError(f"{name}: the file holds no faces ({V.shape[0]} vertices)")
    return V, F


# --------------------------------------------------------------------------------------------
# text helpers


def _text(data: bytes, name: str) -> str:
    if b"\x00" in data[:4096]:
        raise MeshError(f"{name}: binary content where a text file was expected")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _floats(tokens: list[str], name: str, what: str) -> np.ndarray:
    try:
        return np.array(tokens, dtype=np.float64)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise MeshError(f"{name}: {what}: {bad!r} is not a number") from None


def _is_float(t: str) -> bool:
    try:
        float(t)
        return True
    except ValueError:
        return False


def _ints(tokens: list[str], name: str, what: str) -> np.ndarray:
    try:
        return np.array([int(t) for t in tokens], dtype=np.int64)
    except ValueError:
        bad = next(t for t in tokens if not t.lstrip("+-").isdigit())
        raise MeshError(f"{name}: {what}: {bad!r} is not an integer") from None


# --------------------------------------------------------------------------------------------
# OFF


def _read_off(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    text = _text(data, name)
    lines = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if line:
            lines.append(line)
    if not lines:
        raise MeshError(f"{name}: no OFF content")
    head = lines[0].split()
    keyword = head[0]
    if not re.fullmatch(r"(ST)?C?N?4?n?OFF", keyword):
        raise MeshError(f"{name}: not an OFF file (first word is {keyword[:20]!r}, expected 'OFF')")
    if keyword != "OFF" and keyword not in ("COFF", "NOFF", "CNOFF"):
        raise MeshError(f"{name}: OFF variant {keyword!r} is not supported (use OFF, COFF or NOFF)")
    counts = head[1:]
    body = lines[1:]
    if not counts:
        if not body:
            raise MeshError(f"{name}: OFF header has no vertex/face counts")
        counts = body[0].split()
        body = body[1:]
    if len(counts) < 2:
        raise MeshError(f"{name}: OFF header needs vertex and face counts, found {counts}")
    nv_nf = _ints(counts[:2], name, "OFF header counts")
    nv, nf = int(nv_nf[0]), int(nv_nf[1])
    if nv < 0 or nf < 0:
        raise MeshError(f"{name}: OFF header declares negative counts ({nv} vertices, {nf} faces)")
    # Check what the header declares against what the file holds before allocating anything.
    if nv + nf > len(body):
        raise MeshError(
            f"{name}: header declares {nv} vertices and {nf} faces ({nv + nf} lines) but the "
            f"file holds only {len(body)} data lines (truncated, or a wrong header)"
        )
    vtok = [ln.split() for ln in body[:nv]]
    short = [i for i, t in enumerate(vtok) if len(t) < 3]
    if short:
        raise MeshError(f"{name}: vertex {short[0]} has {len(vtok[short[0]])} coordinates, need 3")
    V = _floats([c for t in vtok for c in t[:3]], name, "vertex coordinates").reshape(-1, 3)
    F = _polygon_rows([ln.split() for ln in body[nv : nv + nf]], name)
    return V, F


def _polygon_rows(rows: list[list[str]], name: str) -> np.ndarray:
    """Parse OFF/PLY-ascii style face rows ``k i0 i1 ... ik-1``; only triangles accepted."""
    if not rows:
        return np.zeros((0, 3), dtype=np.int64)
    sizes = [r[0] if r else "" for r in rows]
    nonTri = [i for i, s in enumerate(sizes) if s != "3"]
    if nonTri:
        i = nonTri[0]
        raise MeshError(
            f"{name}: {len(nonTri)} face(s) are not triangles (face {i} starts with "
            f"{sizes[i]!r}); triangulate the mesh first"
        )
    short = [i for i, r in enumerate(rows) if len(r) < 4]
    if short:
        raise MeshError(f"{name}: face {short[0]} lists fewer than 3 vertex indices")
    return _ints([c for r in rows for c in r[1:4]], name, "face indices").reshape(-1, 3)


# --------------------------------------------------------------------------------------------
# OBJ


def _read_obj(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    text = _text(data, name)
    vt: list[str] = []
    ft: list[list[str]] = []
    face_lines: list[int] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        s = raw.strip()
        if s.startswith("v "):
            parts = s.split()
            if len(parts) < 4:
                raise MeshError(f"{name}: line {lineno}: vertex with fewer than 3 coordinates")
            vt.extend(parts[1:4])
        elif s.startswith("f "):
            parts = s.split()[1:]
            if len(parts) != 3:
                raise MeshError(
                    f"{name}: line {lineno}: face with {len(parts)} vertices; only triangles "
                    "are supported (triangulate the mesh first)"
                )
            ft.append([p.split("/", 1)[0] for p in parts])
            face_lines.append(lineno)
    if not vt and not ft:
        raise MeshError(f"{name}: no 'v' or 'f' lines: not an OBJ mesh")
    V = _floats(vt, name, "vertex coordinates").reshape(-1, 3)
    if not ft:
        return V, np.zeros((0, 3), dtype=np.int64)
    idx = _ints([c for r in ft for c in r], name, "face indices").reshape(-1, 3)
    if (idx == 0).any():
        f = int(np.flatnonzero((idx == 0).any(axis=1))[0])
        raise MeshError(f"{name}: line {face_lines[f]}: OBJ vertex index 0 (OBJ counts from 1)")
    # OBJ: 1-based, negative = relative to the vertices read so far.  We resolve negatives
    # against the final count, which is exact for the common files that list all 'v' first.
    F = np.where(idx > 0, idx - 1, V.shape[0] + idx)
    return V, F


# --------------------------------------------------------------------------------------------
# PLY

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


def _read_ply(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise MeshError(f"{name}: not a PLY file (missing 'ply' magic or 'end_header')")
    nl = data.find(b"\n", end)
    body_start = len(data) if nl < 0 else nl + 1
    header = data[:end].decode("latin-1").splitlines()
    fmt = None
    elements: list[dict] = []
    for ln in header[1:]:
        t = ln.split()
        if not t or t[0] in ("comment", "obj_info"):
            continue
        if t[0] == "format" and len(t) >= 2:
            fmt = t[1]
        elif t[0] == "element" and len(t) == 3:
            cnt = _ints([t[2]], name, f"PLY element {t[1]} count")[0]
            if cnt < 0:
                raise MeshError(f"{name}: PLY element {t[1]} has negative count {cnt}")
            elements.append({"name": t[1], "count": int(cnt), "props": []})
        elif t[0] == "property" and elements:
            if t[1] == "list" and len(t) == 5:
                if t[2] not in _PLY_TYPES or t[3] not in _PLY_TYPES:
                    raise MeshError(f"{name}: PLY property {t[4]}: unknown type")
                elements[-1]["props"].append((t[4], _PLY_TYPES[t[2]], _PLY_TYPES[t[3]]))
            elif len(t) == 3 and t[1] in _PLY_TYPES:
                elements[-1]["props"].append((t[2], _PLY_TYPES[t[1]], None))
            else:
                raise MeshError(f"{name}: PLY header line not understood: {ln.strip()!r}")
        else:
            raise MeshError(f"{name}: PLY header line not understood: {ln.strip()!r}")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise MeshError(f"{name}: PLY format {fmt!r} not supported")
    names = [e["name"] for e in elements]
    if "vertex" not in names or "face" not in names:
        raise MeshError(f"{name}: PLY file needs 'vertex' and 'face' elements, has {names}")
    body = data[body_start:]
    if fmt == "ascii":
        return _ply_ascii(body, elements, name)
    return _ply_binary(body, elements, "<" if fmt == "binary_little_endian" else ">", name)


def _face_prop(el: dict, name: str) -> str:
    lists = [p for p in el["props"] if p[2] is not None]
    for p in lists:
        if p[0] in ("vertex_indices", "vertex_index"):
            return p[0]
    raise MeshError(f"{name}: PLY face element has no 'vertex_indices' list property")


def _vertex_cols(el: dict, name: str) -> list[int]:
    pn = [p[0] for p in el["props"]]
    missing = [c for c in "xyz" if c not in pn]
    if missing:
        raise MeshError(f"{name}: PLY vertex element lacks properties {missing}")
    return [pn.index(c) for c in "xyz"]


def _ply_ascii(body: bytes, elements: list[dict], name: str):
    lines = [ln for ln in body.decode("latin-1").splitlines() if ln.strip()]
    need = sum(e["count"] for e in elements)
    if need > len(lines):
        raise MeshError(
            f"{name}: header declares {need} element rows but the file holds {len(lines)} lines "
            "(truncated, or a wrong header)"
        )
    pos = 0
    V = F = None
    for el in elements:
        rows = [ln.split() for ln in lines[pos : pos + el["count"]]]
        pos += el["count"]
        if el["name"] == "vertex":
            cols = _vertex_cols(el, name)
            if any(len(r) < len(el["props"]) for r in rows):
                raise MeshError(f"{name}: a PLY vertex row has too few values")
            V = _floats([r[c] for r in rows for c in cols], name, "vertex").reshape(-1, 3)
        elif el["name"] == "face":
            fp = _face_prop(el, name)
            k = [p[0] for p in el["props"]].index(fp)
            if k != 0 and any(p[2] is not None for p in el["props"][:k]):
                raise MeshError(f"{name}: PLY face rows with several lists are not supported")
            F = _polygon_rows([r[k:] for r in rows], name)
    return V, F


def _ply_binary(body: bytes, elements: list[dict], endian: str, name: str):
    pos = 0
    V = F = None
    for el in elements:
        cnt = el["count"]
        props = el["props"]
        has_list = any(p[2] is not None for p in props)
        if not has_list:
            dt = np.dtype([(p[0], endian + p[1]) for p in props])
        else:
            # Fast path: every list has exactly 3 items (triangles); verified below.
            fields = []
            for p in props:
                if p[2] is None:
                    fields.append((p[0], endian + p[1]))
                else:
                    fields.append((p[0] + "__n", endian + p[1]))
                    fields.append((p[0], endian + p[2], (3,)))
            dt = np.dtype(fields)
        need = cnt * dt.itemsize
        if pos + need > len(body):
            raise MeshError(
                f"{name}: header declares {cnt} {el['name']} rows ({need} bytes from byte "
                f"{pos}) but the body holds only {len(body)} bytes (truncated, or not all "
                "faces are triangles)"
            )
        arr = np.frombuffer(body, dtype=dt, count=cnt, offset=pos)
        if has_list:
            for p in props:
                if p[2] is not None:
                    nonTri = np.flatnonzero(arr[p[0] + "__n"] != 3)
                    if len(nonTri):
                        raise MeshError(
                            f"{name}: {el['name']} {int(nonTri[0])} has a list of "
                            f"{int(arr[p[0] + '__n'][nonTri[0]])} entries; only triangles are "
                            "supported"
                        )
        pos += need
        if el["name"] == "vertex":
            _vertex_cols(el, name)
            V = np.stack([arr[c].astype(np.float64) for c in "xyz"], axis=1)
        elif el["name"] == "face":
            F = arr[_face_prop(el, name)].astype(np.int64)
    return V, F


# --------------------------------------------------------------------------------------------
# STL


def _read_stl(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if len(data) == 84 + 50 * n:
            rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
            arr = np.frombuffer(data, dtype=rec, count=n, offset=84)
            V = arr["v"].reshape(-1, 3).astype(np.float64)
            return V, np.arange(3 * n, dtype=np.int64).reshape(-1, 3)
    head = data[:512].lstrip().lower()
    if head.startswith(b"solid") and b"\x00" not in data[:512]:
        text = _text(data, name)
        toks = re.findall(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", text)
        if not toks:
            raise MeshError(f"{name}: ASCII STL with no 'vertex' lines")
        if len(toks) % 3:
            raise MeshError(f"{name}: ASCII STL has {len(toks)} vertices, not a multiple of 3")
        V = _floats([c for t in toks for c in t], name, "vertex").reshape(-1, 3)
        return V, np.arange(V.shape[0], dtype=np.int64).reshape(-1, 3)
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        raise MeshError(
            f"{name}: binary STL header declares {n} triangles ({84 + 50 * n} bytes) but the "
            f"file has {len(data)} bytes (truncated or not an STL file)"
        )
    raise MeshError(f"{name}: too short to be an STL file ({len(data)} bytes)")
