"""Robust mode scored in-process on a benchmark set: quicker than ``surface_table.py`` (no CLI
process per part), the same metrics and bars (``surface_table.score``).

Each part of ``SET/manifest.json`` is segmented with ``segment_robust`` in a worker process and
scored against its B-Rep labels and types; one JSON line per part goes to ``OUT`` (the metrics,
the pass bars, seconds, and the type confusions over 0.5 % of the area, ``true>predicted``), and
a summary line to stdout. A mesh the strict check refuses (a generated coarse export with
non-manifold vertices) is segmented repaired, as ``--repair`` would, scored on its input faces,
and its row says what was wrong (``repaired``). ``REPO`` (environment) puts another checkout
first on ``sys.path`` (a ``git worktree`` of the commit to compare with); ``SAVE_LABELS`` (a
folder) keeps each part's labels as ``NAME.npy``.

Usage::

    python benchmarks/robust_score.py /tmp/val.jsonl /work/parts/validation
    REPO=/tmp/old python benchmarks/robust_score.py /tmp/val_old.jsonl /work/parts/validation
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import multiprocessing
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
_HERE = Path(__file__).resolve().parent
REPO = Path(os.environ.get("REPO", _HERE.parent))
sys.path[:0] = [str(REPO), str(_HERE), str(_HERE.parent / "tools")]


def score_part(args) -> dict:
    """Segment one manifest entry in robust mode and score it."""
    import numpy as np
    import surface_table as st

    import igl_heatseg as ih

    folder, entry = args
    part = st.load_part(Path(folder), entry)
    t0 = time.perf_counter()
    repaired = None
    try:  # a generated part the strict check refuses is repaired, as `--repair` would
        try:
            mesh = ih.validate_mesh(part["V"], part["F"])
        except ih.MeshError as e:
            mesh = ih.validate_mesh(part["V"], part["F"], repair=True)
            repaired = str(e).split(" (use --repair")[0]
        seg = ih.segment_robust(mesh)
    except Exception as e:  # a benchmark row, not a crash of the whole run
        return dict(name=entry["name"], error=repr(e))
    seconds = time.perf_counter() - t0
    labels = mesh.input_face_labels(seg.labels)  # the input's faces, which the truth labels
    types = [s.kind for s in seg.surfaces] if seg.surfaces is not None else None
    if (labels < 0).any():  # input faces repair dropped with no neighbour: one unfitted segment
        labels = np.where(labels < 0, labels.max() + 1, labels)
        types = None if types is None else types + ["freeform"]
    row = st.score(part, labels, types)
    if repaired:
        row["repaired"] = repaired
    if types is not None and part.get("kinds") is not None:
        pk, tk = st.face_kinds(labels, types), part["kinds"]
        share = part["area"] / part["area"].sum()
        conf: dict = {}
        for t, p, a in zip(tk, pk, share, strict=True):
            if t != p:
                conf[f"{t}>{p}"] = conf.get(f"{t}>{p}", 0.0) + float(a)
        row["confusion"] = {k: round(v, 4) for k, v in sorted(conf.items(), key=lambda x: -x[1])
                            if v > 0.005}
    if os.environ.get("SAVE_LABELS"):
        out = Path(os.environ["SAVE_LABELS"])
        out.mkdir(parents=True, exist_ok=True)
        np.save(out / f"{entry['name']}.npy", labels)
    row.update(name=entry["name"], family=entry.get("family"), tess=entry.get("tessellation"),
               noise=entry.get("noise"), seconds=round(seconds, 2),
               true_faces=int(part["labels"].max()) + 1)
    return json.loads(json.dumps(row, default=lambda o: o.item() if hasattr(o, "item") else o))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("sets", nargs="+", help="set folders with manifest.json")
    ap.add_argument("--only", nargs="+", default=None, help="parts whose name contains any")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    tasks = []
    for folder in a.sets:
        for e in json.loads((Path(folder) / "manifest.json").read_text())["parts"]:
            if not a.only or any(o in e["name"] for o in a.only):
                tasks.append((folder, e))
    rows = []
    pool = concurrent.futures.ProcessPoolExecutor(
        a.jobs, mp_context=multiprocessing.get_context("spawn"))
    with open(a.out, "w") as fo, pool as ex:
        for r in ex.map(score_part, tasks):
            rows.append(r)
            fo.write(json.dumps(r) + "\n")
            fo.flush()
    ok = [r for r in rows if "error" not in r]

    def mean(k):
        v = [r[k] for r in ok if r.get(k) is not None]
        return sum(v) / len(v) if v else float("nan")

    bars = " ".join(f"{b}={sum(r['pass_' + b] for r in ok)}"
                    for b in ("pc", "seg", "bnd", "type", "all"))
    print(f"n={len(ok)} err={len(rows) - len(ok)} purity={mean('purity'):.3f} "
          f"coverage={mean('coverage'):.3f} type={mean('type_acc'):.3f} "
          f"bnd_mean={mean('bnd_ratio'):.2f} {bars} sec={sum(r['seconds'] for r in ok):.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
