"""``igl-heatseg evaluate MESH --truth LABELS``: purity, coverage, the PSB metrics, the boundary
length ratio and (given surface types) the surface-type accuracy."""

from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..evaluation.metrics import Evaluation, evaluate_labels, read_labels, read_truth
from ..evaluation.surfaces import SURFACE_TYPES_SUFFIX, read_surface_types
from ..io import load_mesh
from ..segmentation import segment_with_mode

__all__ = ["register"]

log = logging.getLogger(__name__)


def _format_evaluation(
    ev: Evaluation, mesh_name: str, truth_name: str, types_note: str | None = None
) -> str:
    rows = [
        ("mesh", mesh_name),
        ("truth", f"{truth_name} ({ev.n_truths} labeling(s), {ev.n_true_segments:g} segments)"),
        ("faces", str(ev.n_faces)),
        ("segments", str(ev.n_segments)),
        ("weighting", ev.weighting),
        ("purity (higher better)", f"{ev.purity:.4f}"),
        ("coverage (higher better)", f"{ev.coverage:.4f}"),
        ("rand index, area-weighted", f"{ev.rand_index:.4f}"),
        ("PSB cut discrepancy", f"{ev.cut_discrepancy:.4f}"),
        ("PSB hamming (Rm, Rf)", f"{ev.hamming:.4f} ({ev.hamming_rm:.4f}, {ev.hamming_rf:.4f})"),
        ("PSB 1 - rand index", f"{ev.psb_rand_index:.4f}"),
        ("PSB GCE / LCE", f"{ev.gce:.4f} / {ev.lce:.4f}"),
        ("boundary length ratio (1 best)", f"{ev.boundary_ratio:.4f}"),
        ("segments / true segments", f"{ev.segment_ratio:.4f}"),
    ]
    if ev.type_accuracy is not None:
        rows.append(("surface type accuracy, area", f"{ev.type_accuracy:.4f}"))
    elif types_note:
        rows.append(("surface type accuracy, area", f"- ({types_note})"))
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows) + "\n"


def default_types_path(truth: str | Path) -> Path | None:
    """``NAME.surface_types.txt`` beside a truth file ``NAME.facelabels.txt`` (or ``NAME.EXT``).

    Returns
    -------
    Path or None
        The file when it exists; ``None`` for a truth directory or when there is none.
    """
    truth = Path(truth)
    if truth.is_dir():
        return None
    name = truth.name
    stem = name[: -len(".facelabels.txt")] if name.endswith(".facelabels.txt") else truth.stem
    path = truth.with_name(stem + SURFACE_TYPES_SUFFIX)
    return path if path.exists() else None


def _report_types(labels_path: Path) -> list | None:
    """``type`` of each entry of ``surfaces`` in the ``report.json`` beside a labels file."""
    report = labels_path.parent / "report.json"
    if not report.exists():
        return None
    try:
        surfaces = json.loads(report.read_text()).get("surfaces")
    except (OSError, ValueError, AttributeError) as exc:
        raise MeshError(f"{report}: cannot read the report: {exc}") from None
    if not isinstance(surfaces, list):
        return None
    try:
        return [s["type"] for s in surfaces]
    except (TypeError, KeyError):
        raise MeshError(f"{report}: every entry of 'surfaces' needs a 'type'") from None


def run(args) -> int:
    """Score predicted labels (or a fresh segmentation) against the truth; print the table."""
    t0 = time.perf_counter()
    try:
        # Scoring given labels needs only the faces: no geometric checks (a mesh with
        # zero-area faces is scored as it is); segmenting needs the full checks (or --repair).
        scoring = args.pred is not None
        mesh = load_mesh(
            args.mesh, checks="indices" if scoring else "all", repair=args.repair and not scoring
        )
        m = mesh.n_input_faces
        truths = read_truth(args.truth, m)
        # Labels are per input face; the scores are computed on the triangles, each taking
        # the label of its input face (faces dropped by --repair are not scored).
        fmap = np.arange(mesh.F.shape[0]) if mesh.face_map is None else mesh.face_map
        if scoring:
            pred_path = Path(args.pred)
            if pred_path.is_dir():
                pred_path = pred_path / "labels.txt"
            pred = read_labels(pred_path, m)[fmap]
            pred_types = _report_types(pred_path)
        else:
            seg = segment_with_mode(mesh, args.mode)
            pred = seg.labels
            surfaces = getattr(seg, "surfaces", None)
            pred_types = None if surfaces is None else [s.kind for s in surfaces]
        types_path = Path(args.types) if args.types else default_types_path(args.truth)
        truth_types = None
        if types_path is not None:
            n_true = max(int(t.max()) + 1 for t in truths) if m else 0
            truth_types = read_surface_types(types_path, n_true)
        note = None
        if truth_types is not None and pred_types is None:
            note = "the prediction has no surface types"
        elif truth_types is None and pred_types is not None:
            note = "no true surface types: --types"
        truths = [t[fmap] for t in truths]
        ev = evaluate_labels(
            mesh.V,
            mesh.F,
            pred,
            truths,
            weighting=args.weighting,
            pred_types=pred_types,
            truth_types=truth_types,
        )
    except MeshError as exc:
        sys.stderr.write(f"igl-heatseg evaluate: error: {exc}\n")
        return 2
    if args.json:
        d = ev.as_dict()
        d["types_file"] = None if types_path is None else str(types_path)
        sys.stdout.write(json.dumps(d, indent=2) + "\n")
    else:
        sys.stdout.write(_format_evaluation(ev, str(args.mesh), str(args.truth), note))
    log.info("evaluate: %.2f s", time.perf_counter() - t0)
    return 0


def register(subparsers) -> None:
    """Add ``igl-heatseg evaluate MESH --truth LABELS_OR_DIR [--pred DIR] [--mode robust]``.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``; the subcommand sets ``func`` (``args -> int``).
    """
    p = subparsers.add_parser(
        "evaluate",
        help="score a segmentation against ground-truth face labels",
        description=(
            "Compare per-face labels with a ground truth: purity, coverage, Rand index, the "
            "Princeton Segmentation Benchmark metrics (averaged over several truths), the "
            "boundary length ratio (predicted over true boundary length) and, when both the "
            "prediction and the truth have surface types, the area share typed right."
        ),
    )
    p.add_argument("mesh", help="mesh file (labels refer to its face order)")
    p.add_argument(
        "--truth",
        required=True,
        help="label file (one integer per line: PSB .seg, ABC facelabels.txt) or a directory "
        "of .seg files (several human segmentations, scores averaged)",
    )
    p.add_argument(
        "--pred",
        default=None,
        help="directory holding labels.txt written by `igl-heatseg segment` (or the labels "
        "file itself); default: segment the mesh with the paper's defaults",
    )
    p.add_argument(
        "--types",
        default=None,
        metavar="TYPES_FILE",
        help="true surface type of every truth label ('k Type' per line, ABC "
        "surface_types.txt); default: NAME.surface_types.txt beside the truth NAME.facelabels"
        ".txt when it exists. Scored against the types of the prediction: 'surfaces' in the "
        "report.json beside --pred, or robust mode's fitted surfaces",
    )
    p.add_argument(
        "--mode",
        choices=("paper", "robust"),
        default="paper",
        help="without --pred: segment with the paper's mode (default) or robust mode",
    )
    p.add_argument(
        "--weighting",
        choices=("area", "count"),
        default="area",
        help="face weights of purity, coverage, Rand index, Hamming, GCE/LCE (default area)",
    )
    p.add_argument(
        "--repair",
        action="store_true",
        help="without --pred: repair the mesh before segmenting it (as `segment --repair`); "
        "with --pred no repair is needed (only the face count is checked)",
    )
    p.add_argument("--json", action="store_true", help="print the scores as JSON")
    p.set_defaults(func=run)
