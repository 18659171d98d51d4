"""Parameterize a disk chart: Hessian eigenmap, certified bijectivity, ordered fallbacks.

:func:`parameterize_chart` (ALGORITHM.md sections 6-7) runs an ordered list of attempts
(:func:`attempt_plan`), each run only when the state left by the earlier ones asks for it:

1. ``hessian-hlle`` / ``hessian-curved`` (:func:`~.eigenmap.hessian_map`), then the
   bijectivity certificate (:func:`~.bijectivity.certify_map`).  A mirror image is turned over
   (``u -> -u``), not counted as flipped.  Under ``energy="auto"`` HLLE comes first and the
   curved Hessian runs only when HLLE is not bijective; a free test first skips HLLE on charts
   whose total absolute Gaussian curvature exceeds :data:`HLLE_SKIP_CURVATURE` (noisy scans,
   strongly doubly curved charts), recorded in ``attempts``.
2. ``+repair``: if no Hessian map is bijective and the best one only has local defects (flips,
   no boundary overlap), :func:`~.fallback.repair_map` re-solves a small region around them; a
   certified result that raises the symmetric Dirichlet energy by at most
   :data:`~.fallback.REPAIR_MAX_SD_RATIO` is ``"hessian-<energy>+repair"``.
3. ``tutte``: otherwise a mean-value Tutte map (bijective by construction), improved by
   ``tutte+slim`` (free boundary, guarded: the last bijective iterate is kept); only if no
   iterate is bijective, ``tutte+slim-fixed`` (boundary held on the circle).
4. Quality (``choose="quality"``, the default; issue 13): when the bijective Hessian map's
   symmetric Dirichlet energy is above :data:`QUALITY_TRY_ABOVE`, ``<hessian>+slim`` (SLIM
   started from it) and ``tutte+slim`` are computed too (and ``start``/``start+slim`` from a
   given map); the certified bijective map of lowest energy is kept unless the Hessian map
   is within :data:`HESSIAN_MARGIN` of it, and it is scaled to the chart's true size (UV area
   = 3D area).  Every attempt records its ``sym_dirichlet``.

The map is computed on the chart scaled to unit area and scaled back at the end.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Callable, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from .bijectivity import Certificate
from .distortion import distortion
from .eigenmap import hessian_map
from .fallback import (
    REPAIR_MAX_SD_RATIO,
    SLIM_ITERATIONS,
    SLIM_STOP_AFTER_BAD,
    repair_map,
    slim_guarded,
    tutte_map,
)
from .prepare import (
    BLAS_THREADS,
    PreparedChart,
    certify_oriented,
    expand_uv,
    limit_blas_threads,
    prepare_chart,
    total_abs_curvature,
)

__all__ = [
    "ChartParam",
    "Candidate",
    "Attempt",
    "attempt_plan",
    "parameterize_chart",
    "HLLE_SKIP_CURVATURE",
    "HESSIAN_MARGIN",
    "QUALITY_TRY_ABOVE",
    "CHOICES",
    "ENERGIES",
    "FALLBACKS",
]

log = logging.getLogger(__name__)

#: ``energy="auto"`` skips the HLLE map of a chart whose total absolute Gaussian curvature
#: (:func:`~.prepare.total_abs_curvature`, the sum of the absolute angle defects of its
#: interior vertices; scale-invariant) exceeds this: ``8 pi``, a Gauss image covering the
#: sphere twice.  Measured on the 219 charts of 18 meshes (fandisk, block, the shared data
#: set's mechanical, organic and scan meshes): no HLLE map above 13.3 was bijective (the largest
#: among the 123 bijective ones: block chart 0, 13.2; then psb_352_bearing chart 0, 9.1); all
#: 31 charts above 8 pi failed HLLE (flips or a collapsed map), among them 17 of iron.ply's 41
#: scan charts (noise makes every angle defect count: 131k of its 160k faces; 6.2 of 7.6 s of
#: failed HLLE attempts).  The skip is recorded in ``attempts``.
HLLE_SKIP_CURVATURE: float = 8.0 * np.pi

#: Quality choice (``choose="quality"``): the bijective Hessian map is kept when its symmetric
#: Dirichlet energy is at most this factor above the best bijective candidate's (the paper's
#: map stays the answer where it is good).
HESSIAN_MARGIN: float = 1.02

#: Symmetric Dirichlet energy of an isometry (every map has at least this).
SD_ISOMETRY: float = 4.0

#: Alternatives to a bijective Hessian map (SLIM started from it, Tutte + SLIM) are computed
#: only when its energy is above this: ``SD_ISOMETRY * HESSIAN_MARGIN``, below which no
#: candidate can beat it by more than the margin (every map has energy >= 4).
QUALITY_TRY_ABOVE: float = SD_ISOMETRY * HESSIAN_MARGIN

#: Quality candidates stop SLIM once an iteration lowers the symmetric Dirichlet energy by
#: less than this fraction (:func:`~.fallback.slim_guarded`'s ``stall``).
SLIM_STALL: float = 1e-3

#: Values of ``choose`` accepted by :func:`parameterize_chart`.
CHOICES: tuple[str, ...] = ("quality", "first")

#: Values of ``energy`` accepted by :func:`parameterize_chart`.
ENERGIES: tuple[str, ...] = ("hlle", "curved", "auto")

#: Values of ``fallback`` accepted by :func:`parameterize_chart`.
FALLBACKS: tuple[str, ...] = ("tutte+slim", "tutte", "none")


@dataclass
class ChartParam:
    """A chart's map to the plane and how good it is.

    Attributes
    ----------
    UV : (n, 2) float64
        Image of every vertex of the input ``V`` (``NaN`` rows for vertices ``F`` does not use).
        Counter-clockwise image orientation when the map is bijective (mirror undone).
    method : str
        What produced ``UV``: ``"hessian-hlle"``, ``"hessian-curved"`` (bijective Hessian map),
        ``"hessian-hlle+repair"``, ``"hessian-curved+repair"`` (locally repaired),
        ``"tutte"``, ``"tutte+slim"``, ``"tutte+slim-fixed"`` (fallbacks), or a baseline of
        :func:`~.methods.map_chart`: ``"harmonic"``, ``"lscm"``, ``"arap"``.
    bijective : bool
        Certificate verdict for ``UV``.
    flips, overlaps : int
        Flipped triangles and intersecting boundary-edge pairs of ``UV``.
    distortion : dict
        See :func:`~.distortion.distortion`.
    seconds : float
        Wall time of the whole call (all attempts).
    eigenvalues : (k,) float64 or None
        Lowest generalized eigenvalues of the Hessian attempt (unit-area chart), constant
        included; ``None`` when no Hessian map was tried.
    certificate : Certificate
        Full certificate of ``UV``.
    attempts : list of dict
        Every map tried, in order: method, bijective, flips, overlaps, seconds.
    fallback_used : bool
        True when the requested Hessian map failed the certificate (the chart's map is then a
        repaired Hessian map or a Tutte-based fallback).
    """

    UV: np.ndarray
    method: str
    bijective: bool
    flips: int
    overlaps: int
    distortion: dict
    seconds: float
    eigenvalues: np.ndarray | None = None
    certificate: Certificate | None = field(default=None, repr=False)
    attempts: list = field(default_factory=list)
    fallback_used: bool = False

    def summary(self) -> dict:
        """JSON-ready summary (no arrays except short eigenvalue lists).

        Examples
        --------
        >>> import numpy as np
        >>> p = ChartParam(np.zeros((3, 2)), "tutte", True, 0, 0, {"sym_dirichlet": 4}, 0.1)
        >>> p.summary()["distortion"], p.summary()["degenerate"]
        ({'sym_dirichlet': 4.0}, None)
        """
        return {
            "method": self.method,
            "bijective": bool(self.bijective),
            "flips": int(self.flips),
            "overlaps": int(self.overlaps),
            "degenerate": int(self.certificate.degenerate) if self.certificate else None,
            "fallback_used": bool(self.fallback_used),
            "distortion": {k: float(v) for k, v in self.distortion.items()},
            "seconds": float(self.seconds),
            "eigenvalues": None if self.eigenvalues is None else self.eigenvalues.tolist(),
            "attempts": self.attempts,
        }


@dataclass
class Candidate:
    """A certified map of the unit-area chart (``UV`` indexes :attr:`PreparedChart.V`)."""

    UV: np.ndarray
    cert: Certificate
    method: str
    eigenvalues: np.ndarray | None = None
    sym_dirichlet: float = float("nan")


@dataclass
class _State:
    """What the attempts of one :func:`parameterize_chart` call share."""

    chart: PreparedChart
    name: str
    energy_kwargs: dict
    attempts: list = field(default_factory=list)
    hessian: list = field(default_factory=list)  # Candidates of every Hessian map computed
    current: Candidate | None = None  # the map the chart has now
    total_abs_curvature: float | None = None
    skip_hlle: bool = False
    candidates: list = field(default_factory=list)  # every certified map, for the choice
    start_uv: np.ndarray | None = None  # a given bijective map to start from (compact rows)

    def offer(self, cand: Candidate) -> Candidate:
        """Measure a candidate's symmetric Dirichlet energy and keep it for the choice."""
        c = self.chart
        cand.sym_dirichlet = float(distortion(c.V, c.F, cand.UV)["sym_dirichlet"])
        self.candidates.append(cand)
        return cand

    def best_hessian(self) -> Candidate | None:
        """The bijective Hessian map, else the easiest to repair (no overlaps, fewest local
        defects)."""
        if not self.hessian:
            return None

        def badness(c):
            k = c.cert
            return (not k.bijective, k.overlaps > 0, k.flips + k.degenerate + k.wound)

        return min(self.hessian, key=badness)

    def bijective(self) -> bool:
        return self.current is not None and self.current.cert.bijective


@dataclass(frozen=True)
class Attempt:
    """One step of :func:`attempt_plan`.

    Attributes
    ----------
    method : str
        Name recorded in ``attempts``.
    applies : callable(_State) -> bool
        Whether to run, given the earlier attempts.
    run : callable(_State) -> dict
        Runs the attempt, updates the state, returns its ``attempts`` record (without
        ``seconds``, added by the loop).
    """

    method: str
    applies: Callable
    run: Callable


def _curvature_test(threshold: float) -> Attempt:
    """``energy="auto"``: decide whether HLLE is skipped (a record only when it is)."""

    def run(st: _State) -> dict | None:
        c = st.chart
        st.total_abs_curvature = total_abs_curvature(c.V, c.F, c.boundary)
        st.skip_hlle = st.total_abs_curvature > threshold
        if not st.skip_hlle:
            return None
        tac = st.total_abs_curvature
        return {
            "method": "hessian-hlle",
            "skipped": True,
            "bijective": False,
            "reason": f"total absolute curvature {tac:.3g} > {threshold:.3g}: "
            "HLLE predicted to flip (HLLE_SKIP_CURVATURE)",
            "total_abs_curvature": tac,
        }

    return Attempt("curvature-test", lambda st: True, run)


def _hessian_attempt(energy: str) -> Attempt:
    """A Hessian eigenmap; runs until one is bijective (HLLE not if skipped)."""
    meth = f"hessian-{energy}"

    def applies(st: _State) -> bool:
        if energy == "hlle" and st.skip_hlle:
            return False
        return not any(c.cert.bijective for c in st.hessian)

    def run(st: _State) -> dict:
        c = st.chart
        try:
            kw = st.energy_kwargs if energy == "hlle" else {}
            UV, lam, null_dim = hessian_map(c.V, c.F, energy, **kw)
            ok = bool(np.all(np.isfinite(UV)))
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            if isinstance(exc, MeshError):
                raise
            log.warning("%s: %s eigen-solve failed: %s", st.name, meth, exc)
            ok = False
        if not ok:
            return {"method": meth, "bijective": False, "error": "eigen-solve failed"}
        UV, cert = certify_oriented(UV, c.V, c.F, st.name, [c.boundary])
        cand = st.offer(Candidate(UV, cert, meth, lam))
        st.hessian.append(cand)
        st.current = st.best_hessian()
        tac = st.total_abs_curvature
        return {
            "method": meth,
            **cert.summary(),
            "sym_dirichlet": cand.sym_dirichlet,
            "null_dim": null_dim,
            **({"total_abs_curvature": tac} if tac is not None and energy == "hlle" else {}),
        }

    return Attempt(meth, applies, run)


def _log_fallback(st: _State, fallback: str) -> None:
    cur = st.current
    if cur is not None and not cur.cert.bijective:
        k = cur.cert
        log.info(
            "%s: %s not bijective (flips %d, overlaps %d, degenerate %d, wound %d); "
            "falling back to %s",
            st.name,
            cur.method,
            k.flips,
            k.overlaps,
            k.degenerate,
            k.wound,
            fallback,
        )


def _repair_attempt(fallback: str) -> Attempt:
    """Local repair of the best Hessian map when its only defects are local."""

    def applies(st: _State) -> bool:
        cur = st.current
        return cur is not None and not cur.cert.bijective and cur.cert.overlaps == 0

    def run(st: _State) -> dict:
        c, cur = st.chart, st.current
        UVr, cert_r, rounds = repair_map(cur.UV, c.V, c.F, cur.cert, st.name)
        sd0 = distortion(c.V, c.F, cur.UV)["sym_dirichlet"]
        sd1 = distortion(c.V, c.F, UVr)["sym_dirichlet"]
        keep = cert_r.bijective and sd1 <= REPAIR_MAX_SD_RATIO * sd0
        record = {
            "method": f"{cur.method}+repair",
            "rounds": rounds,
            **cert_r.summary(),
            "sym_dirichlet_ratio": float(sd1 / sd0) if sd0 > 0 else None,
            "kept": bool(keep),
        }
        if keep:
            st.current = st.offer(Candidate(UVr, cert_r, f"{cur.method}+repair", cur.eigenvalues))
            record["sym_dirichlet"] = st.current.sym_dirichlet
        return record

    return Attempt("repair", applies, run)


def _certified_tutte(c, name: str):
    """The chart's Tutte map with Floater's mean value weights, certified; with uniform
    weights when that one is not bijective (``(UV, certificate)``). Both are bijective in
    exact arithmetic; on a noisy housing's 914-face chart the mean value map had 4 flips and
    the uniform one none."""
    UV, cert = certify_oriented(tutte_map(c.V, c.F, c.boundary), c.V, c.F, name, [c.boundary])
    if not cert.bijective:
        UVu, cert_u = certify_oriented(tutte_map(c.V, c.F, c.boundary, "uniform"), c.V, c.F,
                                       name, [c.boundary])
        if cert_u.bijective:
            return UVu, cert_u
    return UV, cert


def _tutte_attempt() -> Attempt:
    def run(st: _State) -> dict:
        c = st.chart
        UV, cert = _certified_tutte(c, st.name)
        lam = st.current.eigenvalues if st.current is not None else None
        st.current = Candidate(UV, cert, "tutte", lam)
        if cert.bijective:
            st.offer(st.current)
        return {"method": "tutte", **cert.summary(), "sym_dirichlet": st.current.sym_dirichlet}

    return Attempt("tutte", lambda st: not st.bijective(), run)


def _slim_attempt(iterations: int, fixed: bool, stall: float | None = None) -> Attempt:
    """Guarded SLIM from the bijective Tutte map: free boundary, or (only when no free-boundary
    iterate was bijective) the boundary held on the circle."""
    meth = "tutte+slim-fixed" if fixed else "tutte+slim"

    def applies(st: _State) -> bool:
        cur = st.current
        if cur is None or cur.method != "tutte" or not cur.cert.bijective or iterations <= 0:
            return False
        last = st.attempts[-1]["method"] if st.attempts else None
        return (last == "tutte+slim") if fixed else (last == "tutte")

    def run(st: _State) -> dict:
        c, start = st.chart, st.current
        bnd = c.boundary if fixed else None
        UV, cert, acc, good = slim_guarded(
            c.V, c.F, start.UV, iterations, st.name, bnd, loops=[c.boundary], stall=stall
        )
        record = {
            "method": meth,
            "accepted_iterations": acc,
            "bijective_iterations": good,
            **(cert.summary() if cert else start.cert.summary()),
        }
        if acc > 0:
            st.current = st.offer(Candidate(UV, cert, meth, start.eigenvalues))
            record["sym_dirichlet"] = st.current.sym_dirichlet
        return record

    return Attempt(meth, applies, run)


def _needs_alternatives(st: _State) -> bool:
    """A bijective Hessian map (repaired or not) whose energy leaves room for a better map."""
    cur = st.current
    return (
        cur is not None
        and cur.method.startswith("hessian-")
        and cur.cert.bijective
        and cur.sym_dirichlet > QUALITY_TRY_ABOVE
    )


def _hessian_slim_attempt(iterations: int) -> Attempt:
    """Quality candidate: guarded SLIM (free boundary) started from the bijective Hessian map."""

    def applies(st: _State) -> bool:
        return iterations > 0 and _needs_alternatives(st)

    def run(st: _State) -> dict:
        c, start = st.chart, st.current
        UV, cert, acc, good = slim_guarded(
            c.V,
            c.F,
            start.UV,
            iterations,
            st.name,
            None,
            loops=[c.boundary],
            stall=SLIM_STALL,
            give_up=SLIM_STOP_AFTER_BAD,
        )
        meth = f"{start.method}+slim"
        record = {"method": meth, "accepted_iterations": acc, "bijective_iterations": good}
        if acc > 0:
            cand = st.offer(Candidate(UV, cert, meth, start.eigenvalues))
            record.update(**cert.summary(), sym_dirichlet=cand.sym_dirichlet)
        else:
            record["bijective"] = False
        return record

    return Attempt("hessian+slim", applies, run)


def _tutte_slim_candidate_attempt(iterations: int) -> Attempt:
    """Quality candidate: Tutte + guarded SLIM next to a bijective Hessian map whose energy
    (even after SLIM from it) leaves room."""

    def applies(st: _State) -> bool:
        if iterations <= 0 or not _needs_alternatives(st):
            return False
        best = min(c.sym_dirichlet for c in st.candidates if c.cert.bijective)
        return best > QUALITY_TRY_ABOVE

    def run(st: _State) -> dict:
        c = st.chart
        UVt, cert_t = _certified_tutte(c, st.name)
        record = {"method": "tutte+slim", "candidate": True}
        if not cert_t.bijective:
            return {**record, **cert_t.summary()}
        UV, cert, acc, good = slim_guarded(
            c.V,
            c.F,
            UVt,
            iterations,
            st.name,
            None,
            loops=[c.boundary],
            stall=SLIM_STALL,
            give_up=SLIM_STOP_AFTER_BAD,
        )
        record.update(accepted_iterations=acc, bijective_iterations=good)
        if acc > 0:
            cand = st.offer(Candidate(UV, cert, "tutte+slim", st.current.eigenvalues))
            record.update(**cert.summary(), sym_dirichlet=cand.sym_dirichlet)
        else:
            record["bijective"] = False
        return record

    return Attempt("tutte+slim-candidate", applies, run)


def _start_attempt(iterations: int) -> Attempt:
    """Quality candidates from a given map (e.g. the parent chart's map restricted to a piece
    cut for distortion): the map itself and SLIM started from it."""

    def run(st: _State) -> dict:
        c = st.chart
        UV0, cert0 = certify_oriented(st.start_uv, c.V, c.F, st.name, [c.boundary])
        record = {"method": "start", **cert0.summary()}
        if not cert0.bijective:
            return record
        lam = st.current.eigenvalues if st.current is not None else None
        record["sym_dirichlet"] = st.offer(Candidate(UV0, cert0, "start", lam)).sym_dirichlet
        if iterations > 0 and record["sym_dirichlet"] > QUALITY_TRY_ABOVE:
            UV, cert, acc, good = slim_guarded(
                c.V,
                c.F,
                UV0,
                iterations,
                st.name,
                None,
                loops=[c.boundary],
                stall=SLIM_STALL,
                give_up=SLIM_STOP_AFTER_BAD,
            )
            if acc > 0:
                cand = st.offer(Candidate(UV, cert, "start+slim", lam))
                record["slim_sym_dirichlet"] = cand.sym_dirichlet
        return record

    return Attempt("start", lambda st: st.start_uv is not None, run)


def _choose(st: _State) -> None:
    """Quality choice among the certified bijective candidates: the lowest symmetric Dirichlet
    energy, unless the Hessian map (the paper's) is within :data:`HESSIAN_MARGIN` of it."""
    good = [c for c in st.candidates if c.cert.bijective and np.isfinite(c.sym_dirichlet)]
    if not good or st.current is None:
        return
    best = min(good, key=lambda c: c.sym_dirichlet)
    cur = st.current
    if cur.cert.bijective and cur.sym_dirichlet <= HESSIAN_MARGIN * best.sym_dirichlet:
        if cur.method.startswith("hessian-"):
            return
    st.current = best


def attempt_plan(
    energy: Literal["hlle", "curved", "auto"] = "hlle",
    fallback: Literal["tutte+slim", "tutte", "none"] = "tutte+slim",
    *,
    slim_iterations: int = SLIM_ITERATIONS,
    repair: bool = True,
    hlle_skip_curvature: float | None = HLLE_SKIP_CURVATURE,
    choose: Literal["quality", "first"] = "quality",
) -> list[Attempt]:
    """The ordered attempts of :func:`parameterize_chart` (each runs only when it applies).

    Parameters
    ----------
    energy, fallback, slim_iterations, repair, hlle_skip_curvature, choose
        As in :func:`parameterize_chart`.

    Returns
    -------
    list of Attempt

    Examples
    --------
    >>> [a.method for a in attempt_plan("auto")]  # doctest: +NORMALIZE_WHITESPACE
    ['curvature-test', 'hessian-hlle', 'hessian-curved', 'repair', 'tutte', 'tutte+slim',
     'tutte+slim-fixed', 'hessian+slim', 'tutte+slim-candidate', 'start']
    >>> [a.method for a in attempt_plan("curved", "none", choose="first")]
    ['hessian-curved']
    """
    plan = []
    if energy == "auto" and hlle_skip_curvature is not None:
        plan.append(_curvature_test(hlle_skip_curvature))
    for en in ("hlle", "curved") if energy == "auto" else (energy,):
        plan.append(_hessian_attempt(en))
    if fallback == "none":
        return plan + ([_hessian_slim_attempt(slim_iterations)] if choose == "quality" else [])
    if repair:
        plan.append(_repair_attempt(fallback))
    plan.append(_tutte_attempt())
    if fallback == "tutte+slim":
        stall = SLIM_STALL if choose == "quality" else None
        plan += [
            _slim_attempt(slim_iterations, False, stall),
            _slim_attempt(slim_iterations, True, stall),
        ]
    if choose == "quality":
        plan += [
            _hessian_slim_attempt(slim_iterations),
            _tutte_slim_candidate_attempt(slim_iterations),
            _start_attempt(slim_iterations),
        ]
    return plan


def parameterize_chart(
    V: ArrayLike,
    F: ArrayLike,
    energy: Literal["hlle", "curved", "auto"] = "hlle",
    *,
    fallback: Literal["tutte+slim", "tutte", "none"] = "tutte+slim",
    slim_iterations: int = SLIM_ITERATIONS,
    repair: bool = True,
    hlle_skip_curvature: float | None = HLLE_SKIP_CURVATURE,
    choose: Literal["quality", "first"] = "quality",
    start_uv: ArrayLike | None = None,
    name: str = "chart",
    **energy_kwargs,
) -> ChartParam:
    """Hessian eigenmap of a disk chart with certified bijectivity and a bijective fallback.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions (vertices not used by ``F`` get ``NaN`` UVs).
    F : (m, 3) array_like of int
        Triangles of a topological disk (1 component, 1 boundary loop, chi = 1), consistently
        oriented.  Any size from one triangle up.
    energy : {"hlle", "curved", "auto"}
        Hessian energy: the paper's HLLE (:func:`~.hessian.hlle_energy`), libigl's curved
        Hessian (:func:`~.hessian.curved_hessian_energy`), or ``"auto"``: HLLE, and the
        curved Hessian when the HLLE map is not bijective (HLLE is the more accurate on
        creased CAD charts, the curved Hessian the more robust on scans).  Under
        ``"auto"``, HLLE is skipped (straight to the curved Hessian) on charts whose
        :func:`~.prepare.total_abs_curvature` exceeds ``hlle_skip_curvature``.
    fallback : {"tutte+slim", "tutte", "none"}
        What to do when the Hessian map is not bijective: a Tutte map (bijective by
        construction), optionally improved by SLIM keeping the last certified-bijective
        iterate (free boundary; with the boundary held on the circle only when no
        free-boundary iterate is bijective); or nothing (return the non-bijective Hessian
        map, flagged).
    slim_iterations : int
        SLIM iterations for ``"tutte+slim"``.
    repair : bool
        Before falling back, try :func:`~.fallback.repair_map` on a Hessian map with local
        flips (no boundary overlaps); if that is bijective the method is
        ``"hessian-<energy>+repair"``.
    hlle_skip_curvature : float or None
        ``energy="auto"`` only: skip HLLE when the chart's total absolute Gaussian curvature
        is above this (default :data:`HLLE_SKIP_CURVATURE`, ``8 pi``; measured: HLLE was never
        bijective above 13.3).  The skipped attempt is listed in ``attempts`` with
        ``"skipped": True`` and the ``reason``.  ``None`` never skips.
    choose : {"quality", "first"}
        ``"quality"`` (default): when the Hessian map is bijective but its symmetric Dirichlet
        energy is above :data:`QUALITY_TRY_ABOVE`, also compute SLIM started from it and
        Tutte + SLIM, and keep the certified bijective map of lowest energy unless the
        Hessian map is within :data:`HESSIAN_MARGIN` of it; every map is scaled to the
        chart's true size (UV area = 3D area).  ``"first"``: the first bijective map of the
        attempt order (the Hessian map's own Gram-corrected scale; Tutte scaled to the area).
    start_uv : (n, 2) array_like of float, optional
        ``choose="quality"`` only: a map of the same chart (rows of ``V``) offered as one more
        candidate (``"start"``), and SLIM started from it (``"start+slim"``), when it is
        bijective, e.g. a parent chart's map restricted to a piece cut for distortion.
    name : str
        Chart name for messages.
    **energy_kwargs
        Passed to :func:`~igl_heatseg.parameterization.hessian.hlle_energy`.

    Returns
    -------
    ChartParam
        ``method`` is ``"hessian-hlle"``/``"hessian-curved"`` when the Hessian map is bijective,
        else ``"tutte"``, ``"tutte+slim"`` or ``"tutte+slim-fixed"`` (``fallback_used=True``);
        ``attempts`` lists every
        map tried with its certificate.  ``UV`` is in the units of ``V`` (Hessian maps are
        isometric-as-possible; the Tutte fallback is scaled to the chart's area).

    Raises
    ------
    MeshError
        Bad arrays, the chart is not a disk, or an unknown ``energy``/``fallback``.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(5.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(20).reshape(4, 5)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 6], 1), np.stack([i, i + 6, i + 5], 1)])
    >>> res = parameterize_chart(V, F)
    >>> res.method, res.bijective, round(res.distortion["sym_dirichlet"], 6)
    ('hessian-hlle', True, 4.0)
    """
    if energy not in ENERGIES:
        raise MeshError(f"{name}: `energy` must be 'hlle', 'curved' or 'auto', got {energy!r}")
    if fallback not in FALLBACKS:
        raise MeshError(
            f"{name}: `fallback` must be 'tutte+slim', 'tutte' or 'none', got {fallback!r}"
        )
    if choose not in CHOICES:
        raise MeshError(f"{name}: `choose` must be 'quality' or 'first', got {choose!r}")
    plan = attempt_plan(
        energy,
        fallback,
        slim_iterations=slim_iterations,
        repair=repair,
        hlle_skip_curvature=hlle_skip_curvature,
        choose=choose,
    )
    with limit_blas_threads(BLAS_THREADS):
        t0 = time.perf_counter()
        st = _State(prepare_chart(V, F, name), name, energy_kwargs)
        if start_uv is not None and choose == "quality":
            st.start_uv = np.asarray(start_uv, dtype=np.float64)[st.chart.used] * st.chart.scale
        _run_plan(st, plan, fallback)
        if choose == "quality":
            _choose(st)
        return _result(st, energy, t0, true_scale=choose == "quality")


def _run_plan(st: _State, plan: list[Attempt], fallback: str) -> None:
    """Run the attempts that apply, in order, recording each with its wall time."""
    logged = False
    for attempt in plan:
        if not attempt.applies(st):
            continue
        if attempt.method in ("repair", "tutte") and not logged:
            _log_fallback(st, fallback)
            logged = True
        t = time.perf_counter()
        record = attempt.run(st)
        if record is not None:
            st.attempts.append({**record, "seconds": time.perf_counter() - t})
    if logged and not st.bijective():
        log.warning(
            "%s: fallback map is not bijective either (%s)", st.name, st.current.cert.summary()
        )


def _result(st: _State, energy: str, t0: float, true_scale: bool = False) -> ChartParam:
    """The chart's :class:`ChartParam` from the final state (scaled back to input units; with
    ``true_scale`` every map, else only the Tutte map, scaled to UV area = 3D area)."""
    c, cur = st.chart, st.current
    if cur is None:  # every eigen-solve failed and no fallback: a zero map, certified
        UV, cert = certify_oriented(np.zeros((c.V.shape[0], 2)), c.V, c.F, st.name)
        cur = Candidate(UV, cert, f"hessian-{energy}")
    UV = cur.UV
    if cur.method == "tutte" or (true_scale and cur.cert.bijective):  # match the chart's area
        d1, d2 = UV[c.F[:, 1]] - UV[c.F[:, 0]], UV[c.F[:, 2]] - UV[c.F[:, 0]]
        a = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum()
        UV = UV / np.sqrt(a)
    return ChartParam(
        UV=expand_uv(UV / c.scale, c.used, c.n_input),
        method=cur.method,
        bijective=cur.cert.bijective,
        flips=cur.cert.flips,
        overlaps=cur.cert.overlaps,
        distortion=distortion(c.V, c.F, UV),
        seconds=time.perf_counter() - t0,
        eigenvalues=cur.eigenvalues,
        certificate=cur.cert,
        attempts=st.attempts,
        fallback_used=cur.method not in ("hessian-hlle", "hessian-curved"),
    )
