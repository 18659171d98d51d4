"""Segmentation benchmark: every labelled mesh x method x noise level -> scores and seconds.

Meshes (all with ground truth):

* the two ABC CAD parts of ``shared/data/mechanical`` (exact B-Rep face labels);
* machined parts from ``tools/make_parts.py`` (exact B-Rep face labels; seeds ``--seeds``);
* the Princeton benchmark meshes with their human segmentations (``*_seg/`` directories;
  coarse semantic parts, scores averaged over the humans).

Each mesh is used clean and with Gaussian noise along the vertex normals of standard deviation
``0.05`` and ``0.1`` times the mean edge length (``--noise``; fixed seed per mesh).

Methods: ``paper`` (:func:`igl_heatseg.segmentation.paper.segment_mesh`, defaults theta = pi/20,
eps = 0.05), ``robust`` (:func:`igl_heatseg.segmentation.robust.segment_robust`, when that module exists),
``dihedral`` (pure dihedral region growing), ``randomwalks`` (Lai et al. 2008 with the paper's
seeds), ``xatlas`` (xatlas charts).

Columns: faces, true segments (mean over truths), segments, area-weighted purity, coverage and
Rand index (:mod:`igl_heatseg.evaluation.metrics`), with ``--psb`` also the PSB cut discrepancy, Hamming
distance, 1 - Rand index, GCE and LCE; ``bij``: share of charts (face-connected pieces of the
segments, cut to disks automatically) whose Hessian eigenmap (:mod:`igl_heatseg.parameterization.param`, no
fallback) passes the bijectivity certificate -- computed only when there are at most
``--max-charts`` charts ("-" otherwise); seconds of the segmentation call.

Usage::

    python benchmarks/segmentation_table.py                   # everything (long)
    python benchmarks/segmentation_table.py --meshes abc parts --methods paper dihedral
    python benchmarks/segmentation_table.py --json out.json --no-bij
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

from igl_heatseg.mesh.checks import validate_mesh  # noqa: E402
from igl_heatseg.evaluation.metrics import evaluate_labels, read_truth  # noqa: E402

#: Where the shared test meshes live (``--data`` overrides).
DATA_DEFAULT = ROOT.parent / "shared" / "data" / "mechanical"

ABC = ("abc_00000006_0", "abc_00007974_5")
PSB = (
    "psb_324_mech",
    "psb_331_mech",
    "psb_340_mech",
    "psb_352_bearing",
    "psb_358_bearing",
    "psb_021_cup",
)
NOISE_DEFAULT = (0.0, 0.05, 0.1)
SEEDS_DEFAULT = (0, 1, 2, 3, 4)
MAX_CHARTS_DEFAULT = 60
METHODS_ALL = ("paper", "robust", "dihedral", "randomwalks", "xatlas")

log = logging.getLogger("segmentation_table")


# --------------------------------------------------------------------------------------------
# Meshes
# --------------------------------------------------------------------------------------------


def labelled_meshes(
    kinds=("abc", "parts", "psb"),
    seeds=SEEDS_DEFAULT,
    data: Path = DATA_DEFAULT,
    target_faces: int = 15000,
    irregular: float = 0.0,
) -> Iterator[tuple[str, np.ndarray, np.ndarray, list]]:
    """Yield ``(name, V, F, truths)`` for every labelled mesh (clean)."""
    from igl_heatseg.io.meshes import load_mesh

    if "abc" in kinds:
        for name in ABC:
            mesh = load_mesh(data / f"{name}.obj")
            yield name, mesh.V, mesh.F, read_truth(data / f"{name}.facelabels.txt", len(mesh.F))
    if "parts" in kinds:
        from make_parts import make_part

        for s in seeds:
            p = make_part(s, target_faces=target_faces, irregular=irregular)
            yield p.name + (f"_irr{irregular:g}" if irregular else ""), p.V, p.F, [p.labels]
    if "psb" in kinds:
        for name in PSB:
            mesh = load_mesh(data / f"{name}.off")
            yield name, mesh.V, mesh.F, read_truth(data / f"{name}_seg", len(mesh.F))


def noisy(V: np.ndarray, F: np.ndarray, fraction: float, seed: int) -> np.ndarray:
    """``V`` with Gaussian noise along the normals (std ``fraction`` x mean edge length)."""
    from make_parts import add_normal_noise

    return V if fraction == 0 else add_normal_noise(V, F, fraction, np.random.default_rng(seed))


# --------------------------------------------------------------------------------------------
# Methods
# --------------------------------------------------------------------------------------------


def available_methods(names=METHODS_ALL) -> dict[str, Callable]:
    """Method name -> ``f(mesh: CleanMesh) -> labels (m,)``, for the methods importable here."""
    out: dict[str, Callable] = {}
    for name in names:
        if name == "paper":
            from igl_heatseg.segmentation.paper import segment_mesh

            out[name] = lambda mesh: segment_mesh(mesh, keep_solvers=False).labels
        elif name == "robust":
            try:
                from igl_heatseg.segmentation.robust import segment_robust
            except ImportError:
                log.warning("igl_heatseg.segmentation.robust not found: no robust row")
                continue
            out[name] = lambda mesh: segment_robust(mesh).labels
        elif name == "dihedral":
            from igl_heatseg.segmentation.baselines import dihedral_region_growing

            out[name] = lambda mesh: dihedral_region_growing(mesh.V, mesh.F)
        elif name == "randomwalks":
            from igl_heatseg.segmentation.baselines import random_walks

            out[name] = lambda mesh: random_walks(mesh.V, mesh.F)
        elif name == "xatlas":
            try:
                import xatlas  # noqa: F401
            except ImportError:
                log.warning("xatlas not installed: no xatlas row")
                continue
            from igl_heatseg.segmentation.baselines import xatlas_charts

            out[name] = lambda mesh: xatlas_charts(mesh.V, mesh.F)
        else:
            raise ValueError(f"unknown method {name!r}")
    return out


def bijective_share(V: np.ndarray, F: np.ndarray, labels: np.ndarray, max_charts: int):
    """Share of charts whose Hessian map (no fallback) is certified bijective.

    Charts are the face-connected pieces of every segment, cut to disks automatically.

    Returns
    -------
    share : float
        ``nan`` when there are more than ``max_charts`` charts or ``igl_heatseg.parameterization.param`` is
        missing.
    n_charts : int
    """
    from igl_heatseg.mesh.topology import face_components

    pieces = []
    for s in np.unique(labels):
        faces = np.flatnonzero(labels == s)
        count, comp = face_components(F[faces])
        pieces += [faces[comp == c] for c in range(count)]
    if len(pieces) > max_charts:
        return math.nan, len(pieces)
    try:
        from igl_heatseg.parameterization.cut import cut_to_disk
        from igl_heatseg.parameterization.param import parameterize_chart
    except ImportError:
        return math.nan, len(pieces)
    good = 0
    for k, fc in enumerate(pieces):
        try:
            cut = cut_to_disk(V, F[fc], name=f"chart {k}")
            res = parameterize_chart(cut.V, cut.F, fallback="none", name=f"chart {k}")
            good += bool(res.bijective)
        except Exception as exc:  # a failed chart counts as not bijective
            log.warning("chart %d (%d faces): %s", k, len(fc), exc)
    return good / len(pieces), len(pieces)


# --------------------------------------------------------------------------------------------
# Table
# --------------------------------------------------------------------------------------------


def run(
    kinds=("abc", "parts", "psb"),
    methods=METHODS_ALL,
    noise=NOISE_DEFAULT,
    seeds=SEEDS_DEFAULT,
    data: Path = DATA_DEFAULT,
    bij: bool = True,
    max_charts: int = MAX_CHARTS_DEFAULT,
    psb_metrics: bool = False,
    target_faces: int = 15000,
    on_row: Callable[[dict], None] | None = None,
    irregular: float = 0.0,
) -> list[dict]:
    """Evaluate every method on every labelled mesh and noise level; return the rows."""
    fns = available_methods(methods)
    rows = []
    for k, (name, V0, F, truths) in enumerate(
        labelled_meshes(kinds, seeds, data, target_faces, irregular)
    ):
        for frac in noise:
            V = noisy(V0, F, frac, seed=1000 + k)
            mesh = validate_mesh(V, F, name=name)
            for meth, fn in fns.items():
                t = time.perf_counter()
                try:
                    labels = fn(mesh)
                except Exception as exc:  # report the failure as a row, keep going
                    log.warning("%s noise %g %s failed: %s", name, frac, meth, exc)
                    rows.append(dict(mesh=name, noise=frac, method=meth, error=str(exc)))
                    continue
                secs = time.perf_counter() - t
                ev = evaluate_labels(mesh.V, mesh.F, labels, truths, cut_metric=psb_metrics)
                row = dict(mesh=name, noise=frac, method=meth, seconds=secs, **ev.as_dict())
                if bij:
                    row["bij"], row["charts"] = bijective_share(mesh.V, mesh.F, labels, max_charts)
                rows.append(row)
                if on_row is not None:
                    on_row(row)
    return rows


def _fmt(v, spec):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return format(v, spec)


def format_table(rows: list[dict], psb_metrics: bool = False) -> str:
    """Markdown table of the rows."""
    cols = [
        ("mesh", "mesh", "s"),
        ("noise", "noise", "g"),
        ("method", "method", "s"),
        ("faces", "n_faces", "d"),
        ("true", "n_true_segments", ".3g"),
        ("segs", "n_segments", "d"),
        ("purity", "purity", ".3f"),
        ("coverage", "coverage", ".3f"),
        ("RI", "rand_index", ".3f"),
    ]
    if psb_metrics:
        cols += [
            ("CD", "cut_discrepancy", ".3f"),
            ("HD", "hamming", ".3f"),
            ("1-RI(PSB)", "psb_rand_index", ".3f"),
            ("GCE", "gce", ".3f"),
            ("LCE", "lce", ".3f"),
        ]
    cols += [("bij", "bij", ".2f"), ("seconds", "seconds", ".2f")]
    out = ["| " + " | ".join(c[0] for c in cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        if "error" in r:
            out.append(f"| {r['mesh']} | {r['noise']:g} | {r['method']} | failed: {r['error']} |")
            continue
        out.append("| " + " | ".join(_fmt(r.get(key), spec) for _, key, spec in cols) + " |")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--meshes", nargs="+", choices=("abc", "parts", "psb"), default=["abc", "parts", "psb"]
    )
    ap.add_argument("--methods", nargs="+", choices=METHODS_ALL, default=list(METHODS_ALL))
    ap.add_argument("--noise", nargs="+", type=float, default=list(NOISE_DEFAULT))
    ap.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS_DEFAULT))
    ap.add_argument("--target-faces", type=int, default=15000)
    ap.add_argument(
        "--irregular", type=float, default=0.0, help="irregular triangulation of the parts"
    )
    ap.add_argument("--data", type=Path, default=DATA_DEFAULT)
    ap.add_argument("--no-bij", action="store_true", help="skip the bijectivity column")
    ap.add_argument("--max-charts", type=int, default=MAX_CHARTS_DEFAULT)
    ap.add_argument("--psb", action="store_true", help="also the PSB metrics (CD, HD, GCE, ...)")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)

    def progress(row):
        sys.stderr.write(
            f"{row['mesh']} noise={row['noise']:g} {row['method']}: {row['n_segments']} segs, "
            f"purity {row['purity']:.3f} coverage {row['coverage']:.3f} "
            f"({row['seconds']:.1f} s)\n"
        )

    t0 = time.perf_counter()
    rows = run(
        args.meshes,
        args.methods,
        args.noise,
        args.seeds,
        args.data,
        not args.no_bij,
        args.max_charts,
        args.psb,
        args.target_faces,
        on_row=progress,
        irregular=args.irregular,
    )
    sys.stdout.write(format_table(rows, args.psb))
    sys.stdout.write(f"\n{len(rows)} rows in {time.perf_counter() - t0:.0f} s\n")
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
