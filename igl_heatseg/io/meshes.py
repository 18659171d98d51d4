"""Mesh readers: OBJ, OFF, PLY and STL files in, a validated :class:`CleanMesh` out.

The readers are our own, not libigl's: libigl's readers accept bad files silently (an OFF
header declaring 99,999,999 vertices in a 30-byte file hangs ``igl.read_triangle_mesh``; an
empty file returns empty arrays).  Every reader checks what the file declares against what it
holds, and raises nothing but :class:`~igl_heatseg.MeshError`: one line naming the file, the
line (text) or byte offset (binary) and what was expected there.  A seeded mutation fuzzer
(``tools/fuzz_readers.py``, and a short run in ``tests/test_io.py``) keeps it that way.

Supported: OBJ, OFF, PLY (ascii, binary little/big endian), STL (ascii, binary).  Polygon
faces (quads, n-gons) are read as they are and triangulated by
:func:`igl_heatseg.mesh.checks.validate_mesh` (a fan per polygon, ``CleanMesh.face_map`` keeps
the input face of every triangle).  STL stores three vertices per face; they are merged by
:func:`~igl_heatseg.mesh.checks.validate_mesh`, which :func:`load_mesh` calls.
"""

from __future__ import annotations

import os
import re
import struct
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..mesh.checks import CleanMesh, validate_mesh

__all__ = ["SUPPORTED_EXTENSIONS", "read_mesh_arrays", "load_mesh"]

SUPPORTED_EXTENSIONS = (".obj", ".off", ".ply", ".stl")

#: Largest vertex count of one polygon face the readers accept.
MAX_POLYGON = 1 << 16

#: Largest absolute value of an integer in a file (counts, indices) before it is "out of range".
_INT_MAX = 1 << 62


def load_mesh(
    path: str | os.PathLike, *, repair: bool = False, checks: str = "all"
) -> CleanMesh:
    """Read a mesh file and validate it.

    Parameters
    ----------
    path : str or path-like
        ``.obj``, ``.off``, ``.ply`` or ``.stl`` file. Polygon faces are triangulated.
    repair : bool
        Repair the defects real exports have instead of refusing them (zero-area and duplicate
        faces, non-manifold vertices and edges, inconsistent orientation, near-duplicate
        vertices); see :func:`igl_heatseg.mesh.repair.repair_mesh`.
    checks : {"all", "indices"}
        ``"indices"`` skips the geometric and topological checks (for scoring labels, which
        needs only the faces): see :func:`~igl_heatseg.mesh.checks.validate_mesh`.

    Returns
    -------
    CleanMesh
        Validated triangle mesh; ``F`` in the file's face order (a polygon's triangles in a
        row), ``vertex_map`` from the file's vertex numbering to the cleaned one, ``face_map``
        from the triangles to the file's faces.

    Raises
    ------
    MeshError
        Missing or unreadable file, unknown extension, malformed content, or a mesh that
        :func:`~igl_heatseg.mesh.checks.validate_mesh` rejects.
    """
    V, F = read_mesh_arrays(path)
    return validate_mesh(V, F, name=Path(path).name, repair=repair, checks=checks)


def read_mesh_arrays(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray | list]:
    """Read vertex and face arrays from a mesh file, without validating the mesh.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64, or (m, k) int64 when every face has ``k`` corners, or a list of ``m``
        int64 arrays when face sizes differ. 0-based; range-checked against ``n``.

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
    try:
        V, sizes, idx = reader(data, name)
    except MeshError:
        raise
    except (ValueError, OverflowError, IndexError, KeyError, TypeError, MemoryError,
            UnicodeError, struct.error) as exc:  # fmt: skip
        # A case the checks above missed: still one line naming the file.
        raise MeshError(
            f"{name}: malformed {ext[1:].upper()} file ({type(exc).__name__}: {exc})"
        ) from None
    if len(sizes) == 0:
        raise MeshError(f"{name}: the file holds no faces ({V.shape[0]} vertices)")
    n = V.shape[0]
    bad_corner = (idx < 0) | (idx >= n)
    if bad_corner.any():
        bad_faces = np.unique(np.repeat(np.arange(len(sizes)), sizes)[bad_corner])
        f = int(bad_faces[0])
        start = int(sizes[:f].sum())
        raise MeshError(
            f"{name}: {len(bad_faces)} face(s) have vertex indices outside 0..{n - 1}: face {f} "
            f"= {idx[start : start + min(int(sizes[f]), 8)].tolist()}"
        )
    return V, _faces(sizes, idx)


def _faces(sizes: np.ndarray, idx: np.ndarray) -> np.ndarray | list:
    k = int(sizes[0])
    if (sizes == k).all():
        return idx.reshape(-1, k)
    return np.split(idx, np.cumsum(sizes)[:-1])


# --------------------------------------------------------------------------------------------
# token helpers

_INT_RE = re.compile(r"[+-]?[0-9]+\Z")


def _text(data: bytes, name: str) -> str:
    k = data.find(b"\x00", 0, 4096)
    if k >= 0:
        raise MeshError(f"{name}: byte {k}: binary content (a NUL byte) in a text file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _int(tok: str, where: str, what: str) -> int:
    """One integer token, in ``-2**62 .. 2**62``."""
    if not _INT_RE.match(tok):
        raise MeshError(f"{where}: {what}: {tok[:30]!r} is not an integer")
    v = int(tok)
    if abs(v) > _INT_MAX:
        raise MeshError(f"{where}: {what}: {tok[:30]} is out of range")
    return v


def _float_array(tokens: list[str], locate, what: str) -> np.ndarray:
    """float64 array of ``tokens``; on a bad token, ``locate(i)`` names where it is."""
    try:
        return np.array(tokens, dtype=np.float64)
    except (ValueError, OverflowError):
        for i, t in enumerate(tokens):
            try:
                float(t)
            except (ValueError, OverflowError):
                raise MeshError(f"{locate(i)}: {what}: {t[:30]!r} is not a number") from None
        raise


def _check_face_size(k: int, where: str) -> None:
    if k < 3:
        raise MeshError(f"{where}: a face needs at least 3 vertices, this one has {k}")
    if k > MAX_POLYGON:
        raise MeshError(f"{where}: a face of {k} vertices (at most {MAX_POLYGON} supported)")


# --------------------------------------------------------------------------------------------
# OFF


def _read_off(data: bytes, name: str):
    text = _text(data, name)
    rows: list[tuple[int, list[str]]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        t = (raw.split("#", 1)[0] if "#" in raw else raw).split()
        if t:
            rows.append((lineno, t))
    if not rows:
        raise MeshError(f"{name}: no OFF content (only comments or blank lines)")
    lineno, head = rows[0]
    keyword = head[0]
    if not re.fullmatch(r"(ST)?C?N?4?n?OFF", keyword):
        raise MeshError(
            f"{name}: line {lineno}: not an OFF file (first word is {keyword[:20]!r}, "
            "expected 'OFF')"
        )
    if keyword not in ("OFF", "COFF", "NOFF", "CNOFF"):
        raise MeshError(
            f"{name}: line {lineno}: OFF variant {keyword!r} is not supported "
            "(use OFF, COFF or NOFF)"
        )
    counts = head[1:]
    body = rows[1:]
    if not counts:
        if not body:
            raise MeshError(f"{name}: line {lineno}: OFF header has no vertex/face counts")
        lineno, counts = body[0]
        body = body[1:]
    where = f"{name}: line {lineno}"
    if len(counts) < 2:
        raise MeshError(f"{where}: OFF header needs vertex and face counts, found {counts[:3]}")
    nv = _int(counts[0], where, "OFF vertex count")
    nf = _int(counts[1], where, "OFF face count")
    if nv < 0 or nf < 0:
        raise MeshError(f"{where}: OFF header declares negative counts ({nv} vertices, {nf} faces)")
    # Check what the header declares against what the file holds before allocating anything.
    if nv + nf > len(body):
        raise MeshError(
            f"{name}: header declares {nv} vertices and {nf} faces ({nv + nf} lines) but the "
            f"file holds only {len(body)} data lines (truncated, or a wrong header)"
        )
    vrows = body[:nv]
    for ln, t in vrows:
        if len(t) < 3:
            raise MeshError(f"{name}: line {ln}: a vertex needs 3 coordinates, found {len(t)}")
    V = _float_array(
        [c for _, t in vrows for c in t[:3]],
        lambda i: f"{name}: line {vrows[i // 3][0]}",
        "vertex coordinate",
    ).reshape(-1, 3)
    sizes, idx = _polygon_rows(body[nv : nv + nf], name)
    return V, sizes, idx


def _polygon_rows(rows: list[tuple[int, list[str]]], name: str):
    """Parse OFF/PLY-ascii face rows ``k i0 i1 ... ik-1 [extra]``: (sizes, flat indices)."""
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    try:
        sizes = np.array([t[0] for _, t in rows], dtype=np.int64)
        ok = bool(((sizes >= 3) & (sizes <= MAX_POLYGON)).all())
    except (ValueError, OverflowError):
        ok = False
    if ok:
        lens = np.array([len(t) for _, t in rows], dtype=np.int64)
        ok = bool((lens > sizes).all())
    if not ok:  # find the first bad row and name it
        for ln, t in rows:
            where = f"{name}: line {ln}"
            k = _int(t[0], where, "face vertex count")
            _check_face_size(k, where)
            if len(t) < k + 1:
                raise MeshError(f"{where}: a face of {k} vertices lists only {len(t) - 1} indices")
    k0 = int(sizes[0])
    if (sizes == k0).all():
        flat = [c for _, t in rows for c in t[1 : k0 + 1]]
    else:
        flat = [c for (_, t), k in zip(rows, sizes.tolist()) for c in t[1 : k + 1]]
    try:
        return sizes, np.array(flat, dtype=np.int64)
    except (ValueError, OverflowError):
        ends = np.cumsum(sizes)
        for i, t in enumerate(flat):
            r = int(np.searchsorted(ends, i, side="right"))
            _int(t, f"{name}: line {rows[r][0]}", "face vertex index")
        raise MeshError(f"{name}: face vertex indices could not be read") from None


# --------------------------------------------------------------------------------------------
# OBJ


def _read_obj(data: bytes, name: str):
    text = _text(data, name)
    vt: list[str] = []
    vlines: list[int] = []
    sizes: list[int] = []
    flat: list[int] = []
    flines: list[int] = []
    nv = 0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        t = (raw.split("#", 1)[0] if "#" in raw else raw).split()
        if not t:
            continue
        if t[0] == "v":
            if len(t) < 4:
                raise MeshError(
                    f"{name}: line {lineno}: a vertex needs 3 coordinates, found {len(t) - 1}"
                )
            vt.extend(t[1:4])
            vlines.append(lineno)
            nv += 1
        elif t[0] == "f":
            where = f"{name}: line {lineno}"
            _check_face_size(len(t) - 1, where)
            for tok in t[1:]:
                i = _int(tok.split("/", 1)[0], where, "face vertex index")
                if i == 0:
                    raise MeshError(f"{where}: OBJ vertex index 0 (OBJ counts from 1)")
                # 1-based (checked against the final count below: a vertex may come after
                # the face using it); negative = relative to the vertices read so far.
                if i < 0 and nv + i < 0:
                    raise MeshError(
                        f"{where}: face vertex index {i} refers to no vertex ({nv} read so far)"
                    )
                flat.append(i - 1 if i > 0 else nv + i)
            sizes.append(len(t) - 1)
            flines.append(lineno)
    if not vt and not sizes:
        raise MeshError(f"{name}: no 'v' or 'f' lines: not an OBJ mesh")
    big = [k for k, j in enumerate(flat) if j >= nv]
    if big:
        f = int(np.searchsorted(np.cumsum(sizes), big[0], side="right"))
        raise MeshError(
            f"{name}: line {flines[f]}: face vertex index {flat[big[0]] + 1} refers to no "
            f"vertex (the file has {nv})"
        )
    V = _float_array(vt, lambda i: f"{name}: line {vlines[i // 3]}", "vertex coordinate")
    return V.reshape(-1, 3), np.array(sizes, dtype=np.int64), np.array(flat, dtype=np.int64)


# --------------------------------------------------------------------------------------------
# PLY

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


def _read_ply(data: bytes, name: str):
    if not re.match(rb"ply[ \t]*\r?\n", data):
        raise MeshError(f"{name}: byte 0: not a PLY file (expected the line 'ply')")
    m = re.search(rb"(^|\n)end_header[ \t]*(\r?\n|\Z)", data)
    if not m:
        raise MeshError(f"{name}: not a PLY file: no 'end_header' line")
    body_start = m.end()
    header = data[: m.start()].decode("latin-1").split("\n")
    fmt = None
    elements: list[dict] = []
    for lineno, ln in enumerate(header[1:], start=2):
        t = ln.split()
        where = f"{name}: line {lineno}"
        if not t or t[0] in ("comment", "obj_info"):
            continue
        if t[0] == "format":
            if len(t) != 3 or t[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise MeshError(
                    f"{where}: PLY format {(t[1] if len(t) > 1 else '')[:40]!r} not supported (expected "
                    "'format ascii|binary_little_endian|binary_big_endian 1.0')"
                )
            fmt = t[1]
        elif t[0] == "element":
            if len(t) != 3:
                raise MeshError(f"{where}: expected 'element NAME COUNT', found {ln.strip()[:60]!r}")
            cnt = _int(t[2], where, f"PLY element {t[1][:20]} count")
            if cnt < 0:
                raise MeshError(f"{where}: PLY element {t[1][:20]} has negative count {cnt}")
            elements.append({"name": t[1], "count": cnt, "props": [], "line": lineno})
        elif t[0] == "property":
            if not elements:
                raise MeshError(f"{where}: PLY property before any element")
            if len(t) >= 2 and t[1] == "list":
                if len(t) != 5:
                    raise MeshError(
                        f"{where}: expected 'property list COUNT_TYPE ITEM_TYPE NAME', "
                        f"found {ln.strip()[:60]!r}"
                    )
                for ty in t[2:4]:
                    if ty not in _PLY_TYPES:
                        raise MeshError(f"{where}: unknown PLY type {ty[:20]!r}")
                if _PLY_TYPES[t[2]][0] == "f":
                    raise MeshError(f"{where}: a PLY list count must be an integer type, not {t[2]}")
                elements[-1]["props"].append((t[4], _PLY_TYPES[t[2]], _PLY_TYPES[t[3]]))
            elif len(t) == 3:
                if t[1] not in _PLY_TYPES:
                    raise MeshError(f"{where}: unknown PLY type {t[1][:20]!r}")
                elements[-1]["props"].append((t[2], _PLY_TYPES[t[1]], None))
            else:
                raise MeshError(
                    f"{where}: expected 'property TYPE NAME', found {ln.strip()[:60]!r}"
                )
        else:
            raise MeshError(f"{where}: PLY header line not understood: {ln.strip()[:60]!r}")
    if fmt is None:
        raise MeshError(f"{name}: PLY header has no 'format' line")
    names = [e["name"] for e in elements]
    for need in ("vertex", "face"):
        if names.count(need) != 1:
            raise MeshError(
                f"{name}: PLY file needs one 'vertex' and one 'face' element, has {names[:8]}"
            )
    for el in elements:
        if not el["props"] and el["count"]:
            raise MeshError(f"{name}: line {el['line']}: PLY element {el['name'][:20]} has no properties")
    _vertex_cols(elements[names.index("vertex")], name)
    _face_prop(elements[names.index("face")], name)
    if fmt == "ascii":
        return _ply_ascii(data, body_start, elements, name, len(header) + 1)
    return _ply_binary(data, body_start, elements, "<" if fmt == "binary_little_endian" else ">", name)


def _face_prop(el: dict, name: str) -> int:
    for k, p in enumerate(el["props"]):
        if p[2] is not None and p[0] in ("vertex_indices", "vertex_index"):
            if p[2][0] == "f":
                raise MeshError(f"{name}: line {el['line']}: PLY face indices must be integers")
            return k
    raise MeshError(
        f"{name}: line {el['line']}: PLY face element has no 'vertex_indices' list property"
    )


def _vertex_cols(el: dict, name: str) -> list[int]:
    pn = [p[0] if p[2] is None else None for p in el["props"]]
    missing = [c for c in "xyz" if c not in pn]
    if missing:
        raise MeshError(
            f"{name}: line {el['line']}: PLY vertex element lacks scalar properties {missing}"
        )
    return [pn.index(c) for c in "xyz"]


def _ply_ascii(data: bytes, body_start: int, elements: list[dict], name: str, first_line: int):
    text = data[body_start:].decode("latin-1")
    rows = [
        (i, t)
        for i, t in ((i, ln.split()) for i, ln in enumerate(text.split("\n"), start=first_line))
        if t
    ]
    need = sum(e["count"] for e in elements)
    if need > len(rows):
        raise MeshError(
            f"{name}: header declares {need} element rows but the file holds {len(rows)} lines "
            "(truncated, or a wrong header)"
        )
    pos = 0
    V = sizes = idx = None
    for el in elements:
        block = rows[pos : pos + el["count"]]
        pos += el["count"]
        props = el["props"]
        if el["name"] == "vertex":
            cols = _vertex_cols(el, name)
            if any(p[2] is not None for p in props[: max(cols) + 1]):
                raise MeshError(f"{name}: line {el['line']}: PLY list before vertex x, y, z")
            for ln, t in block:
                if len(t) < max(cols) + 1:
                    raise MeshError(
                        f"{name}: line {ln}: a PLY vertex row needs {len(props)} values, "
                        f"found {len(t)}"
                    )
            V = _float_array(
                [t[c] for _, t in block for c in cols],
                lambda i: f"{name}: line {block[i // 3][0]}",
                "vertex coordinate",
            ).reshape(-1, 3)
        elif el["name"] == "face":
            k = _face_prop(el, name)
            skip = 0
            frows = []
            for ln, t in block:
                where = f"{name}: line {ln}"
                skip = 0
                for p in props[:k]:  # properties before the index list
                    if p[2] is None:
                        skip += 1
                    else:
                        if len(t) <= skip:
                            raise MeshError(f"{where}: PLY face row too short")
                        skip += 1 + max(0, _int(t[skip], where, "PLY list count"))
                if len(t) <= skip:
                    raise MeshError(f"{where}: PLY face row has no vertex index list")
                frows.append((ln, t[skip:]))
            sizes, idx = _polygon_rows(frows, name)
    return V, sizes, idx


def _ply_binary(data: bytes, pos: int, elements: list[dict], endian: str, name: str):
    V = sizes = idx = None
    for el in elements:
        cnt, props = el["count"], el["props"]
        lists = [p for p in props if p[2] is not None]
        if not lists:
            dt = np.dtype([(f"p{i}", endian + p[1]) for i, p in enumerate(props)])
            need = cnt * dt.itemsize
            if need > len(data) - pos:
                _short(name, el, cnt, pos, need, data)
            arr = np.frombuffer(data, dtype=dt, count=cnt, offset=pos)
            pos += need
            if el["name"] == "vertex":
                cols = _vertex_cols(el, name)
                V = np.stack([arr[f"p{c}"].astype(np.float64) for c in cols], axis=1)
            continue
        arr, pos = _ply_binary_lists(data, pos, el, endian, name)
        if el["name"] == "face":
            k = _face_prop(el, name)
            sizes, idx = arr[k]
            for r in np.flatnonzero((sizes < 3) | (sizes > MAX_POLYGON))[:1]:
                _check_face_size(int(sizes[r]), f"{name}: face {int(r)}")
        elif el["name"] == "vertex":
            cols = _vertex_cols(el, name)
            V = np.stack([arr[c].astype(np.float64) for c in cols], axis=1)
    return V, sizes, idx


def _short(name, el, cnt, pos, need, data):
    raise MeshError(
        f"{name}: byte {pos}: header declares {cnt} {el['name'][:20]} rows ({need} bytes) but "
        f"only {len(data) - pos} bytes are left (truncated, or a wrong header)"
    )


def _ply_binary_lists(data: bytes, pos: int, el: dict, endian: str, name: str):
    """Rows of an element with list properties: per property, the scalar column or the
    (sizes, flat items) of a list. Fast when every row has the same list lengths as the
    first one (all triangles, all quads); row by row otherwise."""
    cnt, props = el["count"], el["props"]
    if cnt == 0:
        return [np.zeros(0) if p[2] is None else (np.zeros(0, np.int64), np.zeros(0, np.int64)) for p in props], pos
    # Lengths of the first row's lists.
    q = pos
    first = []
    for p in props:
        w = np.dtype(p[1]).itemsize
        if q + w > len(data):
            _short(name, el, cnt, pos, q + w - pos, data)
        if p[2] is None:
            q += w
            first.append(None)
        else:
            k = int(np.frombuffer(data, endian + p[1], 1, q)[0])
            if k < 0 or k > MAX_POLYGON:
                raise MeshError(f"{name}: byte {q}: PLY list of {k} items in {el['name'][:20]} 0")
            q += w + k * np.dtype(p[2]).itemsize
            first.append(k)
    fields = []
    for i, (p, k) in enumerate(zip(props, first)):
        if k is None:
            fields.append((f"p{i}", endian + p[1]))
        else:
            fields.append((f"n{i}", endian + p[1]))
            fields.append((f"p{i}", endian + p[2], (k,)))
    dt = np.dtype(fields)
    need = cnt * dt.itemsize
    if need <= len(data) - pos:
        arr = np.frombuffer(data, dtype=dt, count=cnt, offset=pos)
        if all(k is None or (arr[f"n{i}"] == k).all() for i, k in enumerate(first)):
            out = []
            for i, k in enumerate(first):
                if k is None:
                    out.append(arr[f"p{i}"])
                else:
                    out.append((np.full(cnt, k, np.int64), arr[f"p{i}"].astype(np.int64).ravel()))
            return out, pos + need
    # Row by row (mixed polygon sizes), checking every length against what is left.
    cols: list[list] = [[] for _ in props]
    szs: list[list] = [[] for _ in props]
    cache = {}
    for r in range(cnt):
        for i, p in enumerate(props):
            w = np.dtype(p[1]).itemsize
            if pos + w > len(data):
                raise MeshError(
                    f"{name}: byte {pos}: file ends inside {el['name'][:20]} row {r} of {cnt} "
                    "(truncated, or a wrong header)"
                )
            fmt = cache.setdefault(endian + p[1], struct.Struct(endian + np.dtype(p[1]).char))
            v = fmt.unpack_from(data, pos)[0]
            pos += w
            if p[2] is None:
                cols[i].append(v)
                continue
            if v < 0 or v > MAX_POLYGON:
                raise MeshError(f"{name}: byte {pos - w}: PLY list of {v} items in {el['name'][:20]} row {r}")
            iw = np.dtype(p[2]).itemsize
            if pos + v * iw > len(data):
                raise MeshError(
                    f"{name}: byte {pos}: file ends inside {el['name'][:20]} row {r} of {cnt} "
                    "(truncated, or a wrong header)"
                )
            cols[i].append(np.frombuffer(data, endian + p[2], v, pos))
            szs[i].append(v)
            pos += v * iw
    out = []
    for i, p in enumerate(props):
        if p[2] is None:
            out.append(np.array(cols[i]))
        else:
            flat = np.concatenate(cols[i]) if cols[i] else np.zeros(0)
            if flat.dtype.kind == "f" and flat.size and not (np.isfinite(flat).all() and (np.abs(flat) < _INT_MAX).all()):
                raise MeshError(f"{name}: PLY {el['name'][:20]} list {p[0][:20]} holds non-integers")
            out.append((np.array(szs[i], np.int64), flat.astype(np.int64)))
    return out, pos


# --------------------------------------------------------------------------------------------
# STL


def _read_stl(data: bytes, name: str):
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if len(data) == 84 + 50 * n:
            rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
            arr = np.frombuffer(data, dtype=rec, count=n, offset=84)
            V = arr["v"].reshape(-1, 3).astype(np.float64)
            return V, np.full(n, 3, np.int64), np.arange(3 * n, dtype=np.int64)
    head = data[:512].lstrip().lower()
    if head.startswith(b"solid") and b"\x00" not in data[:512]:
        text = _text(data, name)
        matches = list(re.finditer(r"vertex[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", text))
        if not matches:
            raise MeshError(f"{name}: ASCII STL with no 'vertex x y z' lines")
        if len(matches) % 3:
            raise MeshError(
                f"{name}: ASCII STL has {len(matches)} vertices, not a multiple of 3 (a facet "
                "needs 3 'vertex' lines)"
            )
        V = _float_array(
            [c for m in matches for c in m.groups()],
            lambda i: f"{name}: line {text.count(chr(10), 0, matches[i // 3].start()) + 1}",
            "vertex coordinate",
        ).reshape(-1, 3)
        n = V.shape[0] // 3
        return V, np.full(n, 3, np.int64), np.arange(3 * n, dtype=np.int64)
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        raise MeshError(
            f"{name}: byte 80: binary STL header declares {n} triangles ({84 + 50 * n} bytes) "
            f"but the file has {len(data)} bytes (truncated or not an STL file)"
        )
    raise MeshError(f"{name}: too short to be an STL file ({len(data)} bytes, need 84)")
