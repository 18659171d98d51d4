"""The batch's one report: ``summary.csv``, ``summary.json`` and the ``index.html`` gallery.

One record per mesh (:data:`COLUMNS`). Statuses: ``done`` (processed now), ``skipped`` (a complete
output was already there), ``rejected`` (not a valid mesh), ``error`` (the job raised),
``timeout``, ``memory`` (MemoryError under the memory limit), ``crashed`` (the job or its worker
died), ``pending`` (not processed: the batch was interrupted).
"""

from __future__ import annotations

import csv
import html
import io
import json
import os
from pathlib import Path

from ..io.results import COMPLETE_MARKER

__all__ = [
    "COLUMNS",
    "OK_STATUSES",
    "FAILED_STATUSES",
    "skipped_record",
    "counts",
    "write_summary",
    "write_gallery",
    "remove_stale_temporaries",
]

#: Summary columns, in order.
COLUMNS = (
    "mesh",
    "status",
    "reason",
    "faces",
    "segments",
    "charts",
    "bijective",
    "fallback",
    "brep",
    "faceted",
    "hausdorff_pct",
    "volume_error_pct",
    "seconds",
    "peak_memory_mb",
    "output",
)

#: Statuses with a complete output folder.
OK_STATUSES = ("done", "skipped")
#: Statuses of a mesh that has no output (the reason says why).
FAILED_STATUSES = ("rejected", "error", "timeout", "memory", "crashed")


def skipped_record(mesh: str, input_path: str, output: str, summarize) -> dict:
    """The record of a mesh whose output folder is already complete (numbers from its report)."""
    rec = {
        "mesh": mesh,
        "input": input_path,
        "output": output,
        "status": "skipped",
        "reason": "complete output found (--force redoes it)",
    }
    try:
        report = json.loads((Path(output) / COMPLETE_MARKER).read_text())
        rec.update({k: v for k, v in summarize(report).items() if k != "reason"})
        rec["seconds"] = report.get("timings", {}).get("total")
    except (OSError, ValueError):
        pass
    return rec


def counts(records) -> dict:
    """``{status: number}`` over the records, plus ``total``."""
    c: dict[str, int] = {}
    for r in records:
        c[r["status"]] = c.get(r["status"], 0) + 1
    c["total"] = sum(c.values())
    return c


#: The files :func:`_atomic_write` replaces in OUT (``.NAME.PID.tmp`` first).
SUMMARY_FILES = ("summary.csv", "summary.json", "index.html")


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def remove_stale_temporaries(out: str | os.PathLike) -> list:
    """Remove the ``.NAME.PID.tmp`` files of :data:`SUMMARY_FILES` that a batch killed while
    writing its summary left in ``out`` (call it before a batch writes there).

    Parameters
    ----------
    out : path-like
        The batch's output folder (need not exist).

    Returns
    -------
    list of Path
        The files removed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / ".summary.json.123.tmp").write_text("{")
    >>> [p.name for p in remove_stale_temporaries(d)], sorted(p.name for p in d.iterdir())
    (['.summary.json.123.tmp'], [])
    """
    out = Path(out)
    gone = []
    for name in SUMMARY_FILES:
        for p in out.glob(f".{name}.*.tmp"):
            if p.is_file():
                p.unlink(missing_ok=True)
                gone.append(p)
    return gone


def _fmt(v):
    if isinstance(v, float):
        return f"{v:.3f}"
    return "" if v is None else v


def _sorted(records):
    order = {s: i for i, s in enumerate(FAILED_STATUSES + ("pending",) + OK_STATUSES)}
    return sorted(records, key=lambda r: (order.get(r["status"], -1), r["mesh"]))


def write_summary(out: str | os.PathLike, records, meta: dict) -> tuple[Path, Path]:
    """Write ``OUT/summary.csv`` and ``OUT/summary.json`` (each replaced atomically).

    Parameters
    ----------
    out : path-like
    records : list of dict
        One per mesh; the CSV keeps :data:`COLUMNS` (output relative to OUT), the JSON
        everything.
    meta : dict
        Batch facts for the JSON (command, options, workers, wall time...).

    Returns
    -------
    (csv_path, json_path)
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = sorted(records, key=lambda r: r["mesh"])
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        row = {k: _fmt(r.get(k)) for k in COLUMNS}
        if r.get("output"):
            row["output"] = os.path.relpath(r["output"], out)
        w.writerow(row)
    csv_path, json_path = out / "summary.csv", out / "summary.json"
    _atomic_write(csv_path, buf.getvalue())
    doc = dict(meta)
    doc["counts"] = counts(rows)
    doc["meshes"] = rows
    _atomic_write(json_path, json.dumps(doc, indent=1, default=str) + "\n")
    return csv_path, json_path


def write_gallery(out: str | os.PathLike, records, pictures=(), title: str = "") -> Path:
    """Write ``OUT/index.html``: failures on top (with reasons), then one card per mesh with its
    pictures (the first existing of ``pictures`` in its folder) and numbers."""
    out = Path(out)
    e = html.escape
    c = counts(records)
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>{e(title or 'igl-heatseg batch')}</title><style>",
        "body{font-family:sans-serif;margin:1em}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}"
        ".fail{background:#fdd}.grid{display:flex;flex-wrap:wrap;gap:8px}"
        ".card{border:1px solid #ccc;width:260px;padding:4px;font-size:80%}"
        ".card img{width:256px;height:auto}.noimg{height:60px;color:#888}",
        "</style></head><body>",
        f"<h1>{e(title or 'igl-heatseg batch')}</h1>",
        "<p>" + ", ".join(f"{e(k)}: {v}" for k, v in sorted(c.items())) + "</p>",
    ]
    failed = [r for r in _sorted(records) if r["status"] not in OK_STATUSES]
    if failed:
        parts.append(
            f"<h2>Failures ({len(failed)})</h2><table class='fail'>"
            "<tr><th>mesh</th><th>status</th><th>reason</th><th>seconds</th></tr>"
        )
        for r in failed:
            sec = r.get("seconds")
            parts.append(
                f"<tr><td>{e(r['mesh'])}</td><td>{e(r['status'])}</td>"
                f"<td>{e(str(r.get('reason') or ''))}</td>"
                f"<td>{'' if sec is None else f'{sec:.1f}'}</td></tr>"
            )
        parts.append("</table>")
    ok = [r for r in _sorted(records) if r["status"] in OK_STATUSES]
    parts.append(f"<h2>Results ({len(ok)})</h2><div class='grid'>")
    for r in ok:
        folder = Path(r["output"])
        rel = os.path.relpath(folder, out)
        pics = [p for p in pictures if (folder / p).is_file()]
        img = (
            "".join(
                f"<a href='{e(rel)}/{e(p)}'><img loading='lazy' src='{e(rel)}/{e(p)}' "
                f"alt='{e(p)}'></a>"
                for p in pics[:1]
            )
            or "<div class='noimg'>no picture</div>"
        )
        nums = ", ".join(
            f"{k} {r[k]}"
            for k in ("faces", "segments", "charts", "bijective", "fallback", "brep", "faceted",
                      "hausdorff_pct", "volume_error_pct")
            if r.get(k) is not None
        )
        parts.append(
            f"<div class='card'>{img}<div><a href='{e(rel)}/report.json'>{e(r['mesh'])}</a>"
            f"</div><div>{e(nums)}</div></div>"
        )
    parts.append("</div></body></html>\n")
    path = out / "index.html"
    _atomic_write(path, "\n".join(parts))
    return path
