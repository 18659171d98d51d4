#!/usr/bin/env python
"""Mutation fuzzer for the mesh readers, through ``igl-heatseg segment`` run in-process.

Every case is a small valid mesh file (OBJ, OFF, PLY ascii, PLY binary, STL ascii, STL binary;
triangles, and quads where the format has polygons) with one to three seeded mutations: byte
flips, truncations, inserted garbage, huge or malformed numbers, duplicated, removed or swapped
lines, and format-aware header edits. Each file goes through ``igl_heatseg.cli.main(["segment",
FILE, "-o", DIR])`` with stderr captured, and is counted as

``success``    exit 0;
``clean``      exit 2 with exactly one stderr line, ``igl-heatseg: error: ...``;
``multiline``  any other error output (more lines, warnings before the error, no message);
``traceback``  an exception escaped ``main`` (a reader or check raised something else than the
               package's error), or the case ran out of time (``--timeout``).

Usage::

    python tools/fuzz_readers.py --files 5000 [--seed 14] [--repair] [--show 5] [--keep DIR]

The exit code is 1 when any case was a traceback or a multi-line error. The same module gives
the test suite its mutations (``tests/test_io.py`` loads it by path): :func:`base_files`,
:func:`mutate` and :func:`make_case`.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import os
import random
import re
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

FORMATS = ("obj", "off", "ply_ascii", "ply_binary", "stl_ascii", "stl_binary")
EXT = {"obj": ".obj", "off": ".off", "ply_ascii": ".ply", "ply_binary": ".ply",
       "stl_ascii": ".stl", "stl_binary": ".stl"}  # fmt: skip


# --------------------------------------------------------------------------------------------
# base meshes


def _box(n: int = 2, quads: bool = False):
    """A closed axis-aligned box with an ``n x n`` grid per side, outward oriented."""
    V: list = []
    faces: list = []
    index: dict = {}

    def vid(p):
        key = tuple(np.round(p, 9))
        if key not in index:
            index[key] = len(V)
            V.append(p)
        return index[key]

    t = np.linspace(-1.0, 1.0, n + 1)
    for axis in range(3):
        for sign in (-1.0, 1.0):
            a, b = (axis + 1) % 3, (axis + 2) % 3
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = np.zeros(3)
                        p[axis], p[a], p[b] = sign, t[i + di], t[j + dj]
                        q.append(vid(p))
                    if sign < 0:
                        q = q[::-1]
                    if quads:
                        faces.append(q)
                    else:
                        faces.append([q[0], q[1], q[2]])
                        faces.append([q[0], q[2], q[3]])
    V = np.array(V) * np.array([1.0, 0.7, 0.4])
    return V, faces


def _octa():
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return V, F


def write_obj(V, F) -> bytes:
    s = "# fuzz base\no part\n" + "".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in V)
    s += "vt 0 0\nvn 0 0 1\n"
    s += "".join("f " + " ".join(f"{i + 1}/1/1" for i in f) + "\n" for f in F)
    return s.encode()


def write_off(V, F) -> bytes:
    s = f"OFF\n# fuzz base\n{len(V)} {len(F)} 0\n"
    s += "".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in V)
    s += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F)
    return s.encode()


def write_ply(V, F, binary: bool) -> bytes:
    fmt = "binary_little_endian" if binary else "ascii"
    head = (
        f"ply\nformat {fmt} 1.0\ncomment fuzz base\nelement vertex {len(V)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    if not binary:
        body = "".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in V)
        body += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F)
        return head + body.encode()
    out = [head, np.asarray(V, "<f4").tobytes()]
    for f in F:
        out.append(np.uint8(len(f)).tobytes() + np.asarray(f, "<i4").tobytes())
    return b"".join(out)


def write_stl(V, F, binary: bool) -> bytes:
    V = np.asarray(V)
    T = np.array([[V[i] for i in f] for f in F])
    if binary:
        rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
        a = np.zeros(len(T), rec)
        a["v"] = T
        return b"fuzz base".ljust(80, b" ") + np.uint32(len(T)).tobytes() + a.tobytes()
    s = "solid fuzz\n"
    for tri in T:
        s += "  facet normal 0 0 0\n    outer loop\n"
        s += "".join(f"      vertex {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in tri)
        s += "    endloop\n  endfacet\n"
    return (s + "endsolid fuzz\n").encode()


def base_files() -> dict[str, list[bytes]]:
    """Valid files per format: an octahedron, a 2x2 box, and a quad box where polygons exist."""
    out: dict[str, list[bytes]] = {f: [] for f in FORMATS}
    meshes = [_octa(), _box(2)]
    quads = _box(2, quads=True)
    for V, F in meshes:
        out["obj"].append(write_obj(V, F))
        out["off"].append(write_off(V, F))
        out["ply_ascii"].append(write_ply(V, F, False))
        out["ply_binary"].append(write_ply(V, F, True))
        out["stl_ascii"].append(write_stl(V, F, False))
        out["stl_binary"].append(write_stl(V, F, True))
    out["obj"].append(write_obj(*quads))
    out["off"].append(write_off(*quads))
    out["ply_ascii"].append(write_ply(*quads, False))
    out["ply_binary"].append(write_ply(*quads, True))
    return out


# --------------------------------------------------------------------------------------------
# mutations

HUGE = [
    "99999999999999999999999", "-99999999999999999999999", "9223372036854775808",
    "18446744073709551616", "4294967296", "2147483648", "-2147483649", "1e400", "-1e400",
    "1e308", "nan", "inf", "-inf", "-1", "0", "3.5", "0x10", "1e5", "", "+", "-", "1/", "/1",
    "//", "1//2", "1/2/3/4", "\u00e9", "1_000", "٣", "1e-400", "-0", "00000000000000000000001",
]  # fmt: skip
GARBAGE_TOKENS = [
    b"f", b"v", b"3", b"4", b"255", b"f 1 2", b"f 1 2 3 4 5", b"v 1 2", b"vertex", b"facet",
    b"endloop", b"element face 1", b"property float", b"property list uchar",
    b"property list", b"end_header", b"OFF", b"ply", b"solid", b"#", b"\x00", b"\xff\xfe",
    b"\r", b"\t", b"nan", b"1e999", b"-", b"/", b"\\", b"format binary_big_endian 1.0",
]  # fmt: skip
_NUM = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def _header_end(data: bytes) -> int:
    """End of the text part: the PLY header, the STL binary header, or the whole file."""
    k = data.find(b"end_header")
    if data.startswith(b"ply") and k >= 0:
        return data.find(b"\n", k) + 1 or len(data)
    return len(data)


def m_flip(data: bytes, r: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(r.randint(1, 8)):
        if b:
            b[r.randrange(len(b))] ^= 1 << r.randrange(8)
    return bytes(b)


def m_byte(data: bytes, r: random.Random) -> bytes:
    b = bytearray(data)
    if b:
        i = r.randrange(len(b))
        b[i : i + 4] = r.choice(
            [b"\xff\xff\xff\x7f", b"\x00\x00\xc0\x7f", b"\xff\xff\xff\xff", b"\x00\x00\x80\x7f",
             b"\x00", b"\x80\x00\x00\x00", bytes(r.randrange(256) for _ in range(4))]
        )  # fmt: skip
    return bytes(b)


def m_truncate(data: bytes, r: random.Random) -> bytes:
    return data[: r.randrange(len(data) + 1)]


def m_insert(data: bytes, r: random.Random) -> bytes:
    i = r.randrange(len(data) + 1)
    if r.random() < 0.5:
        junk = bytes(r.randrange(256) for _ in range(r.randint(1, 12)))
    else:
        junk = r.choice(GARBAGE_TOKENS) + r.choice([b" ", b"\n", b""])
    return data[:i] + junk + data[i:]


def m_number(data: bytes, r: random.Random) -> bytes:
    """Replace a number in the text part by a huge, negative or malformed one."""
    end = _header_end(data) if data.startswith(b"ply") and b"binary" in data[:60] else len(data)
    nums = list(_NUM.finditer(data[:end]))
    if not nums:
        return m_insert(data, r)
    for _ in range(r.randint(1, 3)):
        m = r.choice(nums)
        new = r.choice(HUGE).encode()
        data = data[: m.start()] + new + data[m.end() :]
        nums = list(_NUM.finditer(data[: min(end, len(data))]))
        if not nums:
            break
    return data


def m_lines(data: bytes, r: random.Random) -> bytes:
    """Duplicate, remove or swap lines (of the header for binary files)."""
    end = _header_end(data)
    text, rest = data[:end], data[end:]
    L = _lines(text)
    if len(L) < 2:
        return m_truncate(data, r)
    op = r.choice(("dup", "del", "swap", "dupmany"))
    i, j = r.randrange(len(L)), r.randrange(len(L))
    if op == "dup":
        L.insert(i, L[j])
    elif op == "del":
        del L[i]
    elif op == "swap":
        L[i], L[j] = L[j], L[i]
    else:
        L[i:i] = [L[j]] * r.randint(2, 50)
    return b"\n".join(L) + rest


def m_header(data: bytes, r: random.Random) -> bytes:
    """Format-aware edits of the header (counts, keywords, types, short lines)."""
    if data.startswith(b"ply"):
        end = _header_end(data)
        L = _lines(data[:end])
        edits = [
            lambda ln: re.sub(rb"(element \w+ )\d+", lambda m: m.group(1) + r.choice(HUGE).encode(), ln),
            lambda ln: b"property " + r.choice([b"", b"float", b"list", b"list uchar", b"list uchar int", b"foo x", b"list uchar foo vertex_indices"]),
            lambda ln: ln.replace(b"float", r.choice([b"double", b"uchar", b"int", b"flaot", b"int8"])),
            lambda ln: ln.replace(b"uchar", r.choice([b"uint", b"char", b"float", b"double"])),
            lambda ln: ln.replace(b"vertex_indices", b"vertex_index" if r.random() < 0.5 else b"idx"),
            lambda ln: r.choice([b"format binary_big_endian 1.0", b"format ascii 1.0", b"format binary_little_endian 1.0", b"format", b"format foo 1.0"]),
            lambda ln: ln.replace(b"element", b"element extra 3\nproperty int q\nelement", 1),
            lambda ln: b"",
        ]  # fmt: skip
        i = r.randrange(1, len(L)) if len(L) > 1 else 0
        L[i] = r.choice(edits)(L[i])
        return b"\n".join(L) + data[end:]
    if data.startswith(b"OFF"):
        L = _lines(data)
        k = 2 if len(L) > 2 else len(L) - 1
        L[k] = r.choice(
            [b"%s %s 0" % (r.choice(HUGE).encode(), r.choice(HUGE).encode()), b"", b"1", b"-1 -1 0",
             b"3 1 0 extra", L[k] + b" 7", b"9999999999 1"]
        )  # fmt: skip
        if r.random() < 0.3:
            L[0] = r.choice([b"COFF", b"NOFF", b"4OFF", b"STOFF", b"OFF 6 8 0", b"OF", b"off"])
        return b"\n".join(L)
    if data.lstrip().startswith(b"solid"):
        t = data.replace(b"vertex", r.choice([b"vertex", b"vertex 1", b"vertexx", b"vertex\n"]), r.randint(1, 3))
        return t if r.random() < 0.7 else b"solid\n" + m_number(t, r)
    if len(data) >= 84 and not data.startswith((b"v", b"#", b"o")):  # binary STL
        n = r.choice([0, 1, 2**31, 2**32 - 1, (len(data) - 84) // 50 + r.choice([-1, 1])])
        head = r.choice([data[:80], b"solid binary".ljust(80), b"\x00" * 80])
        return head + np.uint32(n % 2**32).tobytes() + data[84:]
    # OBJ: face lines with other counts or index forms
    L = _lines(data)
    fl = [i for i, ln in enumerate(L) if ln.startswith(b"f ")]
    if not fl:
        return m_lines(data, r)
    i = r.choice(fl)
    L[i] = r.choice(
        [b"f 1 2", b"f 1 2 3 4 5 6", b"f " + b" ".join(r.choice(HUGE).encode() for _ in range(3)),
         b"f 1/1/1", b"f -1 -2 -3", b"f 0 1 2", b"f a b c", b"f 1 1 1", b"f 1 2 999999999999",
         b"f", b"f 1/ 2/ 3/", b"f //1 //2 //3", b"v 1 2", b"v nan nan nan", b"v 1e400 0 0"]
    )  # fmt: skip
    return b"\n".join(L)


MUTATIONS = (m_flip, m_byte, m_truncate, m_insert, m_number, m_lines, m_header)


def mutate(data: bytes, r: random.Random) -> tuple[bytes, list[str]]:
    """One to three random mutations of ``data``; returns the file and their names."""
    names = []
    for _ in range(r.choice((1, 1, 1, 2, 2, 3))):
        fn = r.choice(MUTATIONS)
        data = fn(data, r)
        names.append(fn.__name__[2:])
    return data, names


_BASES: dict | None = None


def make_case(seed: int, i: int) -> tuple[str, bytes, list[str]]:
    """Case ``i`` of run ``seed``: (format, file bytes, mutation names). Deterministic."""
    global _BASES
    if _BASES is None:
        _BASES = base_files()
    r = random.Random(seed * 1_000_003 + i)
    fmt = FORMATS[i % len(FORMATS)]
    data, names = mutate(r.choice(_BASES[fmt]), r)
    return fmt, data, names


# --------------------------------------------------------------------------------------------
# runner


class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def run_case(path: Path, out: Path, timeout: float, repair: bool = False) -> tuple[str, str]:
    """Run ``igl-heatseg segment path -o out [--repair]`` in-process: (kind, detail)."""
    from igl_heatseg.cli import main

    err, sout = io.StringIO(), io.StringIO()
    logging.root.handlers.clear()  # main's basicConfig binds the stderr of this case
    use_alarm = timeout > 0 and hasattr(signal, "SIGALRM")
    if use_alarm:
        old = signal.signal(signal.SIGALRM, _alarm)
        signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(sout), warnings.catch_warnings():
            warnings.simplefilter("default")  # as a fresh process: each warning shown once
            argv = ["segment", str(path), "-o", str(out), "--progress", "never"]
            rc = main(argv + (["--repair"] if repair else []))
    except _Timeout:
        return "traceback", f"timeout after {timeout:g} s"
    except SystemExit as exc:
        return "multiline", f"SystemExit {exc.code}: {err.getvalue().strip()[:200]!r}"
    except BaseException as exc:  # noqa: BLE001 - that is what is being counted
        tb = traceback.extract_tb(exc.__traceback__)
        where = next(
            (f"{Path(f.filename).name}:{f.lineno}" for f in reversed(tb) if "igl_heatseg" in f.filename),
            f"{Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else "?",
        )
        return "traceback", f"{type(exc).__name__} at {where}: {str(exc)[:120]}"
    finally:
        if use_alarm:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
    if rc == 0:
        return "success", lines[-1] if lines else ""
    if rc == 2 and len(lines) == 1 and lines[0].startswith("igl-heatseg: error: "):
        return "clean", lines[0]
    return "multiline", f"exit {rc}, {len(lines)} lines: " + " | ".join(lines)[:300]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", type=int, default=600, help="number of fuzzed files (default 600)")
    ap.add_argument("--seed", type=int, default=14)
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per file")
    ap.add_argument("--show", type=int, default=3, help="examples shown per failure cause")
    ap.add_argument("--keep", metavar="DIR", help="save failing files into DIR")
    ap.add_argument("--repair", action="store_true", help="run segment with --repair")
    args = ap.parse_args(argv)

    counts: Counter = Counter()
    per_format: dict[str, Counter] = {f: Counter() for f in FORMATS}
    causes: dict[str, list[str]] = {}
    unnamed = 0
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="fuzz_readers_") as tmp:
        tmp = Path(tmp)
        for i in range(args.files):
            fmt, data, names = make_case(args.seed, i)
            path = tmp / f"case{i:05d}{EXT[fmt]}"
            path.write_bytes(data)
            kind, detail = run_case(path, tmp / "out", args.timeout, args.repair)
            counts[kind] += 1
            per_format[fmt][kind] += 1
            if kind == "clean" and path.name not in detail:
                unnamed += 1
                causes.setdefault("clean error not naming the file", []).append(
                    f"case {i} ({fmt}, {'+'.join(names)}): {detail}"
                )
            if kind in ("traceback", "multiline"):
                key = kind + ": " + re.sub(r"case\d+\.\w+", "FILE", detail.split(":")[0] if kind == "traceback" else re.sub(r"\d+", "N", detail[:60]))
                ex = causes.setdefault(key, [])
                ex.append(f"case {i} ({fmt}, {'+'.join(names)}): {detail}")
                if args.keep:
                    Path(args.keep).mkdir(parents=True, exist_ok=True)
                    (Path(args.keep) / path.name).write_bytes(data)
            path.unlink()
    dt = time.perf_counter() - t0
    print(
        f"fuzz_readers: {args.files} files, seed {args.seed}"
        f"{', segment --repair' if args.repair else ''}, {dt:.1f} s"
    )
    print(
        f"  success {counts['success']}, clean error {counts['clean']}, "
        f"multi-line error {counts['multiline']}, traceback {counts['traceback']}"
        f"   (clean errors not naming the file: {unnamed})"
    )
    for fmt in FORMATS:
        c = per_format[fmt]
        print(f"  {fmt:11s} success {c['success']:5d}  clean {c['clean']:5d}  multi-line "
              f"{c['multiline']:4d}  traceback {c['traceback']:4d}")  # fmt: skip
    for key, ex in sorted(causes.items(), key=lambda kv: -len(kv[1])):
        print(f"  [{len(ex)}] {key}")
        for e in ex[: args.show]:
            print(f"      {e[:300]}")
    return 1 if counts["traceback"] or counts["multiline"] else 0


if __name__ == "__main__":
    sys.exit(main())
