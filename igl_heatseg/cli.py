"""Command line: ``igl-heatseg segment MESH -o DIR`` and the other subcommands.

Every subcommand module exposes ``register(subparsers)``; the parser it adds sets ``func``
(``args -> int``).  Bad input (:class:`~igl_heatseg.MeshError`, or a bad parameter value) is
one line on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import time
from pathlib import Path

import numpy as np

from . import __version__
from .constants import EPS_DEFAULT, THETA_DEFAULT
from .errors import MeshError

__all__ = ["main", "Progress", "write_segmentation"]

log = logging.getLogger("igl_heatseg")

#: Modules that add subcommands (each has ``register(subparsers)``), besides ``segment``.
_COMMAND_MODULES = (
    "igl_heatseg.pipeline",
    "igl_heatseg.compare",
    "igl_heatseg.evaluate",
    "igl_heatseg.viz",
)

#: Meshes with at least this many faces get a progress display on stderr by default.
PROGRESS_MIN_FACES = 50_000


class Progress:
    """A minimal progress display on stderr.

    On a terminal the current line is rewritten; otherwise one line is printed per stage and
    per quarter of a long stage, so that CI logs stay short.

    Parameters
    ----------
    enabled : bool
    stream : file-like, optional
        Defaults to ``sys.stderr``.
    """

    def __init__(self, enabled: bool, stream=None) -> None:
        self.enabled = enabled
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self._last: tuple[str, int] | None = None

    def __call__(self, stage: str, fraction: float = 1.0) -> None:
        """Report ``fraction`` (0..1) of ``stage`` done."""
        if not self.enabled:
            return
        pct = int(100 * fraction)
        step = pct if self.tty else 25 * (pct // 25)
        if self._last == (stage, step):
            return
        self._last = (stage, step)
        msg = f"[{time.perf_counter() - self.t0:6.1f}s] {stage}: {pct:3d}%"
        if self.tty:
            self.stream.write("\r" + msg.ljust(60) + ("\n" if pct >= 100 else ""))
        else:
            self.stream.write(msg + "\n")
        self.stream.flush()


def write_segmentation(
    out_dir: Path, mesh, seg, extra: dict | None = None, t_start: float | None = None
) -> dict:
    """Write ``labels.txt``, ``vertex_labels.txt``, ``segmented.ply`` and ``report.json``.

    Parameters
    ----------
    out_dir : Path
        Created if missing.
    mesh : CleanMesh
    seg : Segmentation
    extra : dict, optional
        More report entries (e.g. ``input``, ``timings`` of loading).
    t_start : float, optional
        ``time.perf_counter()`` at the start of the job; sets ``timings["total"]``.

    Returns
    -------
    report : dict
        What was written to ``report.json``.

    Notes
    -----
    ``labels.txt`` has one line per input face, in the input's face order.
    ``vertex_labels.txt`` has one line per input vertex; ``-1`` marks a vertex no face uses.
    ``segmented.ply`` holds the cleaned mesh (duplicate vertices merged) in the input's face
    order, with per-face ``label`` and ``red green blue``.
    """
    from .io import write_labels, write_report, write_segmented_ply

    t = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    write_labels(out_dir / "labels.txt", seg.labels)
    vlab = np.full(mesh.n_input_vertices, -1, dtype=np.int64)
    ref = mesh.vertex_map >= 0
    vlab[ref] = seg.vertex_labels[mesh.vertex_map[ref]]
    write_labels(out_dir / "vertex_labels.txt", vlab)
    write_segmented_ply(out_dir / "segmented.ply", mesh.V, mesh.F, seg.labels)
    report = {
        "igl_heatseg": __version__,
        "faces": int(mesh.F.shape[0]),
        "vertices": int(mesh.n_input_vertices),
        "vertices_used": int(mesh.V.shape[0]),
        "merged_vertices": mesh.merged_vertices,
        "unreferenced_vertices": mesh.unreferenced_vertices,
        "components": seg.components,
        "seedless_components": seg.seedless_components,
        "theta": seg.theta,
        "eps": seg.eps,
        "sharp_edges": int(seg.sharp_edges.shape[0]),
        "seed_vertices": int(seg.seed_mask.sum()),
        "initial_groups": seg.initial_groups,
        "dropped_groups": int(seg.initial_groups - len(seg.kept_groups)),
        "segments": seg.num_segments,
        "segment_areas": seg.segment_areas,
        "segment_faces": np.bincount(seg.labels, minlength=seg.num_segments),
        "initial_segment_areas": np.sort(seg.initial_areas)[::-1],
        "merged_islands": seg.merged_islands,
        "merged_islands_initial": seg.merged_islands_initial,
        "heat_sum_error": seg.heat_sum_error,
    }
    types = getattr(seg, "primitive_types", None)
    report["mode"] = "robust" if types is not None else "paper"
    if types is not None:
        report["primitive_types"] = list(types)
        report["primitive_rms"] = seg.primitive_rms
    report.update(extra or {})
    timings = dict(report.pop("timings", {}))
    timings.update(seg.timings)
    timings["write"] = time.perf_counter() - t
    if t_start is not None:
        timings["total"] = time.perf_counter() - t_start
    report["timings"] = timings
    write_report(out_dir / "report.json", report)
    return report


def _cmd_segment(args: argparse.Namespace) -> int:
    from .io import load_mesh
    from .segment import segment_with_mode

    t0 = time.perf_counter()
    progress = Progress(enabled=False)
    if args.progress == "always":
        progress.enabled = True
    progress("loading", 0.0)
    mesh = load_mesh(args.mesh)
    t_load = time.perf_counter() - t0
    if args.progress == "auto":
        progress.enabled = mesh.F.shape[0] >= PROGRESS_MIN_FACES
    progress("loading", 1.0)
    seg = segment_with_mode(
        mesh, args.mode, args.theta, args.eps, progress=progress, solver=args.solver
    )
    out = Path(args.out)
    extra = {"input": str(Path(args.mesh).resolve()), "timings": {"load": t_load}}
    report = write_segmentation(out, mesh, seg, extra, t_start=t0)
    progress("done", 1.0)
    print(
        f"{Path(args.mesh).name}: {report['faces']} faces, {report['initial_groups']} initial "
        f"groups -> {report['segments']} segments in {report['timings']['total']:.2f} s; "
        f"wrote {out}/",
        file=sys.stderr,
    )
    return 0


def add_segment_arguments(p: argparse.ArgumentParser, with_mode: bool = False) -> None:
    """Add ``--theta`` and ``--eps`` (the paper's two knobs) to a subparser.

    With ``with_mode``, also ``--mode paper|robust``; ``--theta``/``--eps`` then default to
    ``None`` (each mode's own default, see :func:`igl_heatseg.segment.segment_with_mode`).
    """
    from .robust import ROBUST_EPS, ROBUST_THETA

    p.add_argument(
        "--theta",
        type=float,
        default=None if with_mode else THETA_DEFAULT,
        help=f"dihedral threshold in radians; an interior edge whose face normals differ by more "
        f"is sharp (default pi/20 = {THETA_DEFAULT:.4f}"
        + (f"; robust mode: {ROBUST_THETA} on denoised normals)" if with_mode else ")"),
    )
    p.add_argument(
        "--eps",
        type=float,
        default=None if with_mode else EPS_DEFAULT,
        help="area fraction: initial segments smaller than eps x the largest lose their seeds "
        f"(default {EPS_DEFAULT}"
        + (f"; robust mode: {ROBUST_EPS} x the part's area)" if with_mode else ")"),
    )
    if with_mode:
        p.add_argument(
            "--mode",
            choices=("paper", "robust"),
            default="paper",
            help="paper: the paper's method, faithful (default); robust: denoised normals, "
            "curvature-class seeds, part-relative eps and primitive merging, for noisy scans "
            "and blends (adds a primitive type per segment to report.json)",
        )


def add_solver_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--solver fast|exact`` to a subparser."""
    p.add_argument(
        "--solver",
        choices=("fast", "exact"),
        default="fast",
        help="heat solver: fast (certified local solves, same labels; default) or exact "
        "(one global solve per seed group: the reference, slow on noisy scans)",
    )


def build_parser() -> argparse.ArgumentParser:
    """The ``igl-heatseg`` argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="igl-heatseg",
        description="Heat-based segmentation of triangle meshes into parameterizable patches "
        "(Mejia et al. 2018), built on libigl.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser(
        "segment",
        help="segment a mesh (paper §3.1-3.4)",
        description="Segment MESH (.obj .off .ply .stl) and write labels.txt, vertex_labels.txt, "
        "segmented.ply and report.json into DIR.",
    )
    p.add_argument("mesh", help="input mesh file")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_segment_arguments(p, with_mode=True)
    add_solver_argument(p)
    p.add_argument(
        "--progress",
        choices=("auto", "always", "never"),
        default="auto",
        help=f"progress on stderr (auto: for meshes of {PROGRESS_MIN_FACES}+ faces)",
    )
    p.set_defaults(func=_cmd_segment)
    for name in _COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 2 on bad input (one line on stderr), 1 on an unexpected failure.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except (MeshError, ValueError) as exc:
        print(f"igl-heatseg: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"igl-heatseg: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("igl-heatseg: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
