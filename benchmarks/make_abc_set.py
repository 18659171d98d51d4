"""The two shared ABC parts, clean and noisy, as a benchmark set for ``surface_table.py``.

Reads ``abc_00000006_0`` and ``abc_00007974_5`` (``.obj``, ``.facelabels.txt``,
``.surface_types.txt``) from the shared data folder and writes, for each, the clean mesh and
copies with Gaussian noise along the vertex normals of 0.05 and 0.1 x the mean edge length
(``tools/make_parts.add_normal_noise``; seed :data:`NOISE_SEED` for every copy, so the set is
the same on every run), with the labels and types beside them and a ``manifest.json`` in the
format of ``tools/make_benchmark_sets.py``.  The face order is the input's, so the labels stay
valid.

Usage::

    python benchmarks/make_abc_set.py --out /work/parts/abc
    python benchmarks/surface_table.py /work/parts/abc --methods robust cgal --out /tmp/abc

Generated meshes are data: keep them out of the repository.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

import make_parts as mp  # noqa: E402

#: The shared folder holding the ABC parts.
DATA_DEFAULT = Path("/work/shared/data/mechanical")

#: The parts (file stems).
PARTS = ("abc_00000006_0", "abc_00007974_5")

#: Noise levels, as fractions of the mean edge length.
NOISE_LEVELS = (0.0, 0.05, 0.1)

#: Seed of every noisy copy.
NOISE_SEED = 11


def make_set(data: Path, out: Path) -> dict:
    """Write the set; returns the manifest."""
    import igl

    out.mkdir(parents=True, exist_ok=True)
    entries = []
    for stem in PARTS:
        V, F, labels, types = mp.read_part(data / f"{stem}.obj")
        if len(labels) != len(F):
            raise ValueError(f"{stem}: {len(labels)} labels for {len(F)} faces")
        for noise in NOISE_LEVELS:
            name = f"{stem}_n{noise:g}"
            W = V if noise == 0 else mp.add_normal_noise(V, F, noise, NOISE_SEED)
            igl.write_triangle_mesh(str(out / f"{name}.obj"), W, F)
            shutil.copyfile(data / f"{stem}.facelabels.txt", out / f"{name}.facelabels.txt")
            shutil.copyfile(data / f"{stem}.surface_types.txt", out / f"{name}.surface_types.txt")
            kinds, counts = np.unique(np.asarray(types), return_counts=True)
            entries.append(
                dict(
                    name=name,
                    family="abc",
                    seed=NOISE_SEED if noise else None,
                    tessellation="abc",
                    noise=noise,
                    faces=int(len(F)),
                    true_faces=int(labels.max()) + 1,
                    types={str(k): int(c) for k, c in zip(kinds, counts, strict=True)},
                    obj=f"{name}.obj",
                    source=str(data / f"{stem}.obj"),
                )
            )
    manifest = dict(set="abc", noise_seed=NOISE_SEED, parts=entries)
    (out / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def main(argv: list[str] | None = None) -> int:
    """Command line: write the set to ``--out``."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--data", default=str(DATA_DEFAULT), help="folder with the ABC parts")
    args = ap.parse_args(argv)
    m = make_set(Path(args.data), Path(args.out))
    print(f"wrote {len(m['parts'])} parts and manifest.json to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
