"""Score the CAD outputs of ``igl-heatseg batch SET -o OUT --command cad`` on a generated set,
and compare two such runs part by part (the tuning set's harness; ``bench_cad.py`` is the
validation set's, beside mesh2cad).

Per part, from ``OUT/NAME/report.json`` and ``model.step``: segments and faceted segments,
a valid closed solid (BRepCheck, a solid, no free edge), the two-sided Hausdorff distance to
the mesh (the report's) and to the part (to the noise-free mesh of a noisy part, rebuilt from
the set's ``manifest.json`` with ``bench_cad.clean_mesh``), the volume error to the mesh and to
the part (the noise-free mesh's volume: noise is not volume-neutral, the noisy tuning meshes'
volumes are 0.08-0.10 % off their parts' at the median and up to 6 % on coarse noisy parts; a
coarse tessellation's volume is its chords'), the Hausdorff distance and volume error to the
true part (to a dense tessellation of its true surfaces, ``bench_cad.true_part_mesh``: a
coarse export's facets are chords, which an exact B-Rep is not), the seconds, the
border faces the build moved to a neighbouring segment, the B-Rep's faces (a faceted segment
adds one per triangle) and the faceted triangles left out because sewing closed them up.
Then the bars (Hausdorff and volume error <= 0.5 %) and the faceted segments by reason.
The scores are cached in ``OUT/cad_score.json`` (a cache without the true-part measures gets
them added).

Usage::

    igl-heatseg batch /work/parts/tuning -o /tmp/a --command cad --workers 2 --no-pictures
    python benchmarks/cad_batch_score.py /work/parts/tuning /tmp/a            # one run
    python benchmarks/cad_batch_score.py /work/parts/tuning /tmp/a /tmp/b     # before, after
"""

from __future__ import annotations

import argparse
import collections
import json
import re
import sys
from pathlib import Path

_HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(_HERE), str(_HERE.parent / "tools")]

BAR = 0.005


def _reason(text: str | None) -> str:
    """A faceted segment's reason without its numbers ("surface deviates", ...)."""
    return re.split(r"[ (;:]+[-+]?[0-9.]", text or "?")[0].strip()


def score_run(setdir: Path, out: Path, cache: Path) -> dict:
    """Per part name: the metrics above (cached in ``out/cad_score.json``)."""
    manifest = {p["name"]: p for p in json.loads((setdir / "manifest.json").read_text())["parts"]}
    path = out / "cad_score.json"
    scores = json.loads(path.read_text()) if path.exists() else {}
    for d in sorted(p for p in out.iterdir() if (p / "report.json").exists()):
        if d.name in scores and "brep_faces" not in scores[d.name]:  # (a cache of before)
            cad = json.loads((d / "report.json").read_text())["cad"]
            scores[d.name].update(brep_faces=cad["fidelity"]["faces"], dropped=sum(
                f.get("dropped", 0) for f in cad["faces"]))
        if d.name in scores and "vol_part" not in scores[d.name] and d.name in manifest:
            fid = json.loads((d / "report.json").read_text())["cad"]["fidelity"]
            scores[d.name]["vol_part"] = _volume_to_part(fid, manifest[d.name], cache)
            path.write_text(json.dumps(scores, indent=1) + "\n")
        if d.name in scores and "to_true" not in scores[d.name] and d.name in manifest:
            scores[d.name].update(_to_true_part(d, manifest[d.name], cache))
            path.write_text(json.dumps(scores, indent=1) + "\n")
        if d.name in scores or d.name not in manifest:
            continue
        rep = json.loads((d / "report.json").read_text())
        cad, entry = rep["cad"], manifest[d.name]
        fid = cad["fidelity"]
        faceted = [f for f in cad["faces"] if f["status"] != "built"]
        row = dict(segments=len(cad["faces"]), faceted=len(faceted),
                   reasons=dict(collections.Counter(_reason(f["reason"]) for f in faceted)),
                   solid=bool(fid["valid"] and fid["solids"] >= 1 and fid["free_edges"] == 0),
                   hausdorff=fid["hausdorff_rel"], volume=fid["volume_rel_error"],
                   seconds=rep["timings"]["total"], to_part=fid["hausdorff_rel"],
                   moved=len(cad.get("border_faces_moved", [])), brep_faces=fid["faces"],
                   dropped=sum(f.get("dropped", 0) for f in cad["faces"]))
        if entry["noise"] and fid["hausdorff_rel"] is not None:
            from bench_cad import clean_mesh

            from igl_heatseg.cad import brep_fidelity, read_step
            from igl_heatseg.io import load_mesh

            ref = load_mesh(clean_mesh(entry, cache))
            row["to_part"] = brep_fidelity(read_step(d / "model.step"), ref.V,
                                           ref.F)["hausdorff_rel"]
        row["vol_part"] = _volume_to_part(fid, entry, cache)
        row.update(_to_true_part(d, entry, cache))
        scores[d.name] = row
        path.write_text(json.dumps(scores, indent=1) + "\n")
    return scores


def _volume_to_part(fid: dict, entry: dict, cache: Path) -> float | None:
    """Relative volume error of a closed B-Rep to its part: to the noise-free mesh's volume
    for a noisy part, else the report's error to the mesh (None when not closed)."""
    if fid.get("volume") is None:
        return None
    if not entry["noise"]:
        return fid["volume_rel_error"]
    from bench_cad import clean_mesh

    from igl_heatseg.cad.fidelity import mesh_volume
    from igl_heatseg.io import load_mesh

    ref = load_mesh(clean_mesh(entry, cache))
    part = mesh_volume(ref.V, ref.F)
    return abs(fid["volume"] - part) / abs(part)


def _to_true_part(d: Path, entry: dict, cache: Path) -> dict:
    """``to_true`` (two-sided Hausdorff distance over the true part's diagonal) and
    ``vol_true`` (relative volume error, None when the B-Rep is not closed) of ``d/model.step``
    against a dense tessellation of the part's true surfaces."""
    from bench_cad import true_part_mesh

    from igl_heatseg.cad import brep_fidelity, read_step
    from igl_heatseg.io import load_mesh

    ref = load_mesh(true_part_mesh(entry, cache))
    fid = brep_fidelity(read_step(d / "model.step"), ref.V, ref.F)
    return {"to_true": fid["hausdorff_rel"], "vol_true": fid["volume_rel_error"],
            "true_confirmed": fid.get("hausdorff_confirmed", True)}


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.2f}"


def _ok(x) -> bool:
    return x is not None and x <= BAR


def summary(scores: dict) -> dict:
    """Totals and bars of one run."""
    reasons = collections.Counter()
    moved = [r.get("moved", 0) for r in scores.values()]
    dropped = [r.get("dropped", 0) for r in scores.values()]
    for r in scores.values():
        reasons.update(r["reasons"])
    return {"parts": len(scores),
            "faceted segments": f"{sum(r['faceted'] for r in scores.values())} / "
                                f"{sum(r['segments'] for r in scores.values())}",
            "parts without a faceted segment": sum(r["faceted"] == 0 for r in scores.values()),
            "valid closed solids": sum(r["solid"] for r in scores.values()),
            "Hausdorff <= 0.5 % to the mesh": sum(_ok(r["hausdorff"]) for r in scores.values()),
            "Hausdorff <= 0.5 % to the part": sum(_ok(r["to_part"]) for r in scores.values()),
            "volume error <= 0.5 %": sum(_ok(r["volume"]) for r in scores.values()),
            "volume error <= 0.5 % to the part": sum(_ok(r.get("vol_part"))
                                                    for r in scores.values()),
            "Hausdorff <= 0.5 % to the true part": sum(_ok(r.get("to_true"))
                                                      for r in scores.values()),
            "volume error <= 0.5 % to the true part": sum(_ok(r.get("vol_true"))
                                                         for r in scores.values()),
            "true-part Hausdorff an upper bound (parts)": sum(
                r.get("true_confirmed") is False for r in scores.values()),
            "seconds (sum)": round(sum(r["seconds"] for r in scores.values()), 1),
            "parts over 30 s": sum(r["seconds"] > 30 for r in scores.values()),
            "border faces moved (parts)": f"{sum(moved)} ({sum(m > 0 for m in moved)})",
            "B-Rep faces (sum)": sum(r.get("brep_faces") or 0 for r in scores.values()),
            "faceted triangles left out (parts)": f"{sum(dropped)} "
                                                  f"({sum(m > 0 for m in dropped)})",
            "faceted by reason": dict(reasons.most_common())}


def _cell(r: dict | None) -> str:
    if r is None:
        return "missing"
    return (f"faceted {r['faceted']:3d}/{r['segments']:3d} {'solid' if r['solid'] else 'no solid'}"
            f" H {_pct(r['hausdorff'])} to part {_pct(r['to_part'])} vol {_pct(r['volume'])}"
            f" to part {_pct(r.get('vol_part'))}"
            f" true part H {_pct(r.get('to_true'))} vol {_pct(r.get('vol_true'))}"
            f" faces {r.get('brep_faces')} {r['seconds']:.0f} s")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("set", type=Path, help="the set's folder (with manifest.json)")
    ap.add_argument("runs", type=Path, nargs="+", help="one or two batch output folders")
    ap.add_argument("--clean", type=Path, default=None,
                    help="cache of noise-free and true-part meshes (default: SET/../clean)")
    args = ap.parse_args(argv)
    cache = args.clean or args.set.parent / "clean"
    runs = [score_run(args.set, out, cache) for out in args.runs[:2]]
    keys = ("faceted", "solid", "hausdorff", "to_part", "volume", "vol_part", "to_true",
            "vol_true", "brep_faces")
    for name in sorted(set().union(*runs)):
        rows = [run.get(name) for run in runs]
        changed = len(rows) == 2 and (None in rows or any(rows[0][k] != rows[1][k]
                                                          for k in keys))
        if len(rows) == 1 or changed:
            print(f"{name:42s} " + " | ".join(_cell(r) for r in rows))
    for out, run in zip(args.runs, runs, strict=False):
        print(f"\n{out}:")
        for k, v in summary(run).items():
            print(f"  {k}: {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
