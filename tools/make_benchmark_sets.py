"""Tuning and validation sets of labelled machined parts, split by part family AND by seed.

A method's parameters are tuned on ``tuning/`` and judged on ``validation/``.  The two differ

* by family: :data:`VALIDATION_ONLY` families (nut, sprocket, housing, knob, saddle_boss) are
  never in the tuning set; the other families (:data:`TUNING_FAMILIES`) appear in both;
* by seed: tuning parts use seeds ``TUNING_SEED0 + i``, validation parts
  ``VALIDATION_SEED0 + i`` (disjoint ranges), so no shared-family part repeats.

Each part gets one variant, spread across the set so every family sees several: a
tessellation (``frontal``: gmsh Frontal-Delaunay at a target size; ``irregular``: MeshAdapt
with a size field varying by 50-70 %; ``coarse``: OpenCASCADE's CAD-export tessellation with
12-24 segments per circle, slivers on planes, usually under 5k triangles) and a noise level
(0, 0.05, 0.1 or 0.2 x the mean edge length, along the vertex normals).  Target sizes are
drawn log-uniformly in [:data:`MIN_FACES`, :data:`MAX_FACES`].

Output (``OUT/tuning`` and ``OUT/validation``): ``NAME.obj``, ``NAME.facelabels.txt``,
``NAME.surface_types.txt`` per part (see ``tools/make_parts.py``) and ``manifest.json``::

    {"set": "tuning", "split": {...}, "parts": [{"name", "family", "seed", "tessellation",
     "cad_facets", "irregular", "noise", "target_faces", "faces", "true_faces", "types",
     "obj", "seconds"}, ...]}

Usage::

    python tools/make_benchmark_sets.py --out /work/parts            # both sets, 40 parts each
    python tools/make_benchmark_sets.py --out /tmp/sets --per-set 8 --sets tuning
    python tools/make_benchmark_sets.py --out /work/parts_t3 --sets tuning --first-seed 6000

``--first-seed`` makes further sets of the same split: another tuning set (seeds 5000 and
6000 on, tuning-2 and tuning-3) or a fresh validation set (seeds 4000 on). Choose a range
that meets no other set's (the tool does not check).

Generated meshes are data: keep them out of the repository.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import make_parts as mp  # noqa: E402

#: Families held out of tuning: only in the validation set.
VALIDATION_ONLY = ("nut", "sprocket", "housing", "knob", "saddle_boss")

#: Families in both sets (with disjoint seeds).
TUNING_FAMILIES = tuple(k for k in mp.KINDS if k not in VALIDATION_ONLY)

#: First seed of each set; parts take consecutive seeds, so the ranges never meet below 1000
#: parts per set.
TUNING_SEED0, VALIDATION_SEED0 = 1000, 2000

TESSELLATIONS = ("frontal", "irregular", "coarse")
NOISE_LEVELS = (0.0, 0.05, 0.1, 0.2)

#: Parts per set by default (75 s of CPU per set; 4 minutes wall on two busy shared cores).
PER_SET_DEFAULT = 40

#: Range of gmsh target triangle counts (log-uniform); coarse CAD tessellations ignore it.
MIN_FACES, MAX_FACES = 5000, 36000

#: Range of segments per circle of the coarse tessellation.
CAD_FACETS = (12, 24)

#: Range of the size-field strength of the irregular tessellation.
IRREGULAR = (0.5, 0.7)



def set_families(name: str) -> tuple[str, ...]:
    """Families of the ``tuning`` or ``validation`` set.

    Parameters
    ----------
    name : {"tuning", "validation"}

    Returns
    -------
    tuple of str
        Validation: the held-out families first, then the shared ones.
    """
    if name == "tuning":
        return TUNING_FAMILIES
    if name == "validation":
        return VALIDATION_ONLY + TUNING_FAMILIES
    raise ValueError(f"set must be 'tuning' or 'validation', got {name!r}")


def plan_set(name: str, n_parts: int, seed0: int | None = None) -> list[dict]:
    """The parts of one set: family, seed and variant of each, deterministic.

    Parameters
    ----------
    name : {"tuning", "validation"}
    n_parts : int
        Number of parts; families are cycled (validation starts with the held-out ones).
    seed0 : int, optional
        First seed (parts take consecutive seeds); TUNING_SEED0 or VALIDATION_SEED0 by
        default.

    Returns
    -------
    list of dict
        ``family``, ``seed``, ``tessellation``, ``noise``, ``target_faces``, ``cad_facets``,
        ``irregular`` per part.
    """
    if n_parts < 1:
        raise ValueError(f"n_parts must be >= 1, got {n_parts}")
    families = set_families(name)
    if seed0 is None:
        seed0 = TUNING_SEED0 if name == "tuning" else VALIDATION_SEED0
    if seed0 < 0:
        raise ValueError(f"seed0 must be >= 0, got {seed0}")
    plan = []
    for i in range(n_parts):
        seed = seed0 + i
        rng = np.random.default_rng([seed, 7])
        # the k-th part of family f: noise and tessellation both step with k, so every family
        # sees several levels of each, and the set holds about equal counts of every level
        f, k = i % len(families), i // len(families)
        noise = NOISE_LEVELS[(f + k) % len(NOISE_LEVELS)]
        tess = TESSELLATIONS[(f // len(NOISE_LEVELS) + k) % len(TESSELLATIONS)]
        target = int(round(math.exp(rng.uniform(math.log(MIN_FACES), math.log(MAX_FACES)))))
        plan.append(
            dict(
                family=families[i % len(families)],
                seed=seed,
                tessellation=tess,
                noise=noise,
                target_faces=target if tess != "coarse" else None,
                cad_facets=int(rng.integers(CAD_FACETS[0], CAD_FACETS[1] + 1))
                if tess == "coarse"
                else 0,
                irregular=round(float(rng.uniform(*IRREGULAR)), 3) if tess == "irregular" else 0.0,
            )
        )
    return plan


def part_name(entry: dict) -> str:
    """``FAMILY_sSEED_TESSELLATION_nNOISE``, e.g. ``gear_s1011_coarse_n0.1``."""
    return f"{entry['family']}_s{entry['seed']}_{entry['tessellation']}_n{entry['noise']:g}"


def build_part(entry: dict) -> mp.Part:
    """Make the part an entry of :func:`plan_set` describes."""
    return mp.make_part(
        entry["seed"],
        entry["family"],
        target_faces=entry["target_faces"] or mp.TARGET_FACES_DEFAULT,
        irregular=entry["irregular"],
        noise=entry["noise"],
        cad_facets=entry["cad_facets"],
    )


def split_description(name: str | None = None, seed0: int | None = None) -> dict:
    """The split rule, stored in every manifest (with set ``name`` starting at ``seed0``)."""
    firsts = {"tuning": TUNING_SEED0, "validation": VALIDATION_SEED0}
    if name is not None and seed0 is not None:
        firsts[name] = seed0
    return dict(
        validation_only_families=list(VALIDATION_ONLY),
        shared_families=list(TUNING_FAMILIES),
        tuning_seeds_from=firsts["tuning"],
        validation_seeds_from=firsts["validation"],
        tessellations=list(TESSELLATIONS),
        noise_levels=list(NOISE_LEVELS),
        noise_unit="mean edge length, along vertex normals",
    )


def write_set(out: Path, name: str, n_parts: int, seed0: int | None = None) -> dict:
    """Generate one set into ``out/name`` and write its ``manifest.json``.

    Parameters
    ----------
    out : Path
        Parent directory (created if missing).
    name : {"tuning", "validation"}
    n_parts : int
    seed0 : int, optional
        First seed (:func:`plan_set`).

    Returns
    -------
    dict
        The manifest.
    """
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    entries = []
    t_set = time.perf_counter()
    for k, entry in enumerate(plan_set(name, n_parts, seed0)):
        t0 = time.perf_counter()
        part = build_part(entry)
        stem = part_name(entry)
        mp.write_part(part, folder, stem)
        dt = time.perf_counter() - t0
        row = dict(
            name=stem,
            **entry,
            faces=int(len(part.F)),
            true_faces=len(part.surface_types),
            types=dict(sorted(Counter(part.surface_types).items())),
            obj=f"{stem}.obj",
            seconds=round(dt, 2),
        )
        entries.append(row)
        print(
            f"[{name} {k + 1}/{n_parts}] {stem}: {row['faces']} faces, "
            f"{row['true_faces']} B-Rep faces, {dt:.1f} s",
            flush=True,
        )
    manifest = dict(
        set=name,
        split=split_description(name, seed0),
        families=sorted({e["family"] for e in entries}),
        seeds=[e["seed"] for e in entries],
        seconds=round(time.perf_counter() - t_set, 1),
        parts=entries,
    )
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def main(argv: list[str] | None = None) -> int:
    """Command line: write the tuning and validation sets."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="output directory (sets go in OUT/<set>/)")
    ap.add_argument("--per-set", type=int, default=PER_SET_DEFAULT, help="parts per set")
    ap.add_argument(
        "--sets", nargs="+", choices=("tuning", "validation"), default=["tuning", "validation"]
    )
    ap.add_argument(
        "--first-seed", type=int, default=None,
        help="first seed of the set(s) written (default: %d for tuning, %d for validation); "
        "e.g. 6000 for another tuning set" % (TUNING_SEED0, VALIDATION_SEED0),
    )
    args = ap.parse_args(argv)
    if args.per_set < 1:
        ap.error("--per-set must be >= 1")
    if args.first_seed is not None and args.first_seed < 0:
        ap.error("--first-seed must be >= 0")
    for name in args.sets:
        m = write_set(Path(args.out), name, args.per_set, args.first_seed)
        print(
            f"{name}: {len(m['parts'])} parts, {len(m['families'])} families, "
            f"{m['seconds']:.0f} s -> {Path(args.out) / name / 'manifest.json'}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
