"""What every subcommand shares: progress on stderr, the segmentation options, loading."""

from __future__ import annotations

import argparse
import sys
import time

from ..constants import EPS_DEFAULT, THETA_DEFAULT
from ..segmentation.params import MODES, ROBUST_EPS, ROBUST_THETA, SOLVERS

__all__ = [
    "PROGRESS_MIN_FACES",
    "Progress",
    "add_segment_arguments",
    "add_solver_argument",
    "add_progress_argument",
    "progress_for",
    "add_repair_argument",
    "add_time_limit_argument",
    "TIME_LIMIT_DEFAULT",
    "repair_summary",
]

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
    auto : bool
        :meth:`sized` decides ``enabled`` from the mesh size.
    """

    def __init__(self, enabled: bool, stream=None, auto: bool = False) -> None:
        self.enabled = enabled
        self.auto = auto
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self._last: tuple[str, int] | None = None

    def sized(self, n_faces: int) -> Progress:
        """Under ``auto``, turn the display on for meshes of :data:`PROGRESS_MIN_FACES`+ faces."""
        if self.auto:
            self.enabled = n_faces >= PROGRESS_MIN_FACES
        return self

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


def add_segment_arguments(p: argparse.ArgumentParser, mode: str = "paper") -> None:
    """Add ``--mode paper|robust``, ``--theta`` and ``--eps`` to a subparser.

    ``mode`` is the subcommand's default mode (named in the help). ``--theta``/``--eps``
    default to ``None``: each mode's own default, resolved by
    :func:`igl_heatseg.segmentation.params.resolve_params` (the one place they are checked).
    """
    paper, robust = (" (default)", "") if mode == "paper" else ("", " (default)")
    p.add_argument(
        "--mode",
        choices=MODES,
        default=mode,
        help=f"paper: the paper's method, faithful{paper}; robust{robust}: for noisy scans and "
        "blends (denoised normals, curvature-class seeds, part-relative eps, primitive "
        "merging), with one fitted surface per segment (report.json `surfaces`, segmented.ply "
        "surface_type; the segments are refined by the fits: `segment --refine/--no-refine`)",
    )
    p.add_argument(
        "--theta",
        type=float,
        default=None,
        help="dihedral threshold in radians; an interior edge whose face normals differ by more "
        f"is sharp (default pi/20 = {THETA_DEFAULT:.4f}; robust mode: {ROBUST_THETA} on "
        "denoised normals)",
    )
    p.add_argument(
        "--eps",
        type=float,
        default=None,
        help="area fraction: initial segments smaller than eps x the largest of their component "
        f"lose their seeds (default {EPS_DEFAULT}; robust mode: {ROBUST_EPS} x the component's "
        "area)",
    )


def add_solver_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--solver fast|exact`` to a subparser."""
    p.add_argument(
        "--solver",
        choices=SOLVERS,
        default="fast",
        help="heat solver: fast (certified local solves, same labels; default) or exact "
        "(one global solve per seed group: the reference, slow on noisy scans)",
    )


def add_progress_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--progress auto|always|never`` to a subparser."""
    p.add_argument(
        "--progress",
        choices=("auto", "always", "never"),
        default="auto",
        help=f"progress on stderr (auto: for meshes of {PROGRESS_MIN_FACES}+ faces)",
    )


def progress_for(args: argparse.Namespace) -> Progress:
    """The progress display ``--progress`` asks for; under ``auto`` call
    :meth:`Progress.sized` once the mesh is loaded."""
    mode = getattr(args, "progress", "auto")
    return Progress(enabled=mode == "always", auto=mode == "auto")


def add_repair_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--repair`` to a subparser (``load_mesh(path, repair=True)``)."""
    p.add_argument(
        "--repair",
        action="store_true",
        help="repair what exports get wrong instead of refusing the mesh: weld near-duplicate "
        "vertices, drop zero-area and duplicate faces, split non-manifold vertices and edges, "
        "orient each component consistently (outward when closed); every change is counted in "
        "report.json `repairs`, outputs stay in the input's face and vertex order (a dropped "
        "face takes the label across its longest edge, -1 when there is none)",
    )


#: ``cad`` and ``run --step``: seconds after which the B-Rep build starts no further rebuild,
#: unless ``--time-limit`` says otherwise (the batch's half of its 600 s timeout; no tuning or
#: validation part came near it, a fresh 40k-triangle housing took over 15 minutes without it).
TIME_LIMIT_DEFAULT = 300.0


def _seconds(text: str) -> float | None:
    """argparse type: a non-negative, finite number of seconds; 0 is None (no limit)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not (value >= 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(
            f"must be a number of seconds >= 0 (0: no limit), got {text!r}")
    return value or None


def add_time_limit_argument(p: argparse.ArgumentParser, prefix: str = "") -> None:
    """Add ``--time-limit S`` (the B-Rep build's ``time_limit``, counted from the start;
    default :data:`TIME_LIMIT_DEFAULT`, 0 for none)."""
    p.add_argument(
        "--time-limit",
        type=_seconds,
        default=TIME_LIMIT_DEFAULT,
        metavar="S",
        help=f"{prefix}seconds from the start after which the B-Rep build starts no further "
        "rebuild or second pass: the model it has is written (a still invalid one faceted), "
        "and report.json `cad.time_limit` says what was skipped (default "
        f"{TIME_LIMIT_DEFAULT:g}; 0 for no limit)",
    )


def repair_summary(mesh) -> str:
    """`` (3 polygon faces split; repaired: 2 nonmanifold vertices, ...)`` or ``""``."""
    parts = []
    if mesh.split_faces:
        parts.append(f"{mesh.split_faces} polygon faces triangulated")
    done = [
        f"{v} {k.replace('_', ' ')}"
        for k, v in mesh.repairs.items()
        if v and k not in ("weld_tolerance", "dropped_faces_unlabelled")
    ]
    if done:
        parts.append("repaired: " + ", ".join(done))
    elif mesh.repairs:
        parts.append("nothing to repair")
    return f" ({'; '.join(parts)})" if parts else ""
