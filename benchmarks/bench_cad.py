"""B-Rep benchmark: ``igl-heatseg cad`` beside mesh2cad on the validation parts and the ABC parts.

For every part both tools write a STEP file; both files are read back (``read_step``) and
scored the same way against the mesh the tool was given
(:func:`igl_heatseg.cad.brep_fidelity`): valid closed solid, faces, two-sided Hausdorff over
the bounding-box diagonal, volume error, wall seconds of the tool's command.  An *exact B-Rep*
is a valid closed solid with fewer faces than :data:`EXACT_FACE_SHARE` of the mesh's
triangles (a faceted fallback has about one face per triangle); for ours the faceted segments
are counted too.

Parts: the validation set's noise 0 and 0.1 parts (``--set all``) or a stratified subset of
ten (``--set subset``: five per noise level, coarse to 32k triangles, :data:`SUBSET`), and the
two ABC parts clean and with Gaussian noise of 0.1 x the mean edge length along the normals
(``tools/make_parts.add_normal_noise``, seed 11 as in ``make_abc_set.py``).

mesh2cad (PyPI, MIT) needs Python >= 3.12 and OCP < 8: it gets its own venv (``--m2c-venv``,
created with pyenv's 3.12 interpreter when missing, then ``pip install mesh2cad``) and runs as
``mesh2cad convert PART.obj -o PART.step`` with a :data:`M2C_TIMEOUT` s timeout.  The two
tools run side by side (two queues, one process each) on the same machine.  Each result
records the commit it was run at and when; a cached result of ours from another commit is run
again, and the table's header says at which commits its rows were run and whether the two
tools ran side by side.

Results are cached per tool and part in ``WORK/results`` (a rerun continues); ``--table``
only writes the table from the cache. The table goes to ``WORK/cad_results.md`` unless
``--md`` names another file (``benchmarks/cad_results.md`` keeps the measured history by hand:
the table is pasted into it, not written over it).

Usage::

    python benchmarks/bench_cad.py --work /tmp/bench_cad --set subset
    python benchmarks/bench_cad.py --work /tmp/bench_cad --table --figures
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

VALIDATION = Path("/work/parts/validation")
ABC_DATA = Path("/work/shared/data/mechanical")
ABC_PARTS = ("abc_00000006_0", "abc_00007974_5")
ABC_NOISE = 0.1
NOISE_SEED = 11
NOISE_LEVELS = (0.0, 0.1)

#: Stratified subset of the validation parts: five per noise level, 268 to 31.7k triangles.
SUBSET = (
    "rounded_box_s2021_coarse_n0.1",
    "bracket_s2023_coarse_n0",
    "domed_cap_s2010_coarse_n0.1",
    "flange_s2008_coarse_n0",
    "saddle_boss_s2004_irregular_n0",
    "bolt_s2012_frontal_n0",
    "pipe_elbow_s2014_frontal_n0.1",
    "plate_s2006_irregular_n0.1",
    "block_s2025_frontal_n0.1",
    "countersunk_plate_s2027_frontal_n0",
)

#: mesh2cad's timeout per part (seconds); ours gets OURS_TIMEOUT.
M2C_TIMEOUT = 300
OURS_TIMEOUT = 900

#: Issue 12's bar on the Hausdorff distance (share of the bbox diagonal).
HAUSDORFF_BAR = 0.005

#: A valid solid with fewer faces than this share of the mesh's triangles is an exact B-Rep.
EXACT_FACE_SHARE = 0.1

#: pyenv's Python 3.12 (the bare ``python3.12`` shim fails unless PYENV_VERSION is set).
PYENV_312 = Path.home() / ".pyenv" / "versions"


def _python312() -> str:
    cands = sorted(PYENV_312.glob("3.12*/bin/python3.12")) if PYENV_312.exists() else []
    for c in cands:
        return str(c)
    exe = shutil.which("python3.12")
    if exe:
        env = dict(os.environ, PYENV_VERSION=os.environ.get("PYENV_VERSION", "3.12.1"))
        if subprocess.run([exe, "-V"], env=env, capture_output=True).returncode == 0:
            return exe
    raise SystemExit("bench_cad: no Python 3.12 found for mesh2cad's venv")


def ensure_m2c(venv: Path) -> Path:
    """mesh2cad's executable in its own venv (created when missing)."""
    exe = venv / "bin" / "mesh2cad"
    if not exe.exists():
        subprocess.run([_python312(), "-m", "venv", str(venv)], check=True)
        subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "mesh2cad"], check=True)
    return exe


def clean_mesh(entry: dict, folder: Path) -> str:
    """The noise-free tessellation of a generated noisy part (same seed and mesh, noise 0:
    ``make_parts`` adds the noise after meshing), written once to ``folder/NAME.obj``
    (``cad_batch_score.py`` uses it too)."""
    import igl
    import make_benchmark_sets as mbs

    path = folder / f"{entry['name']}.obj"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        part = mbs.build_part(dict(entry, noise=0.0))
        igl.write_triangle_mesh(str(path), np.asarray(part.V, np.float64),
                                np.asarray(part.F, np.int64))
    return str(path)


#: Triangles of the dense tessellation that stands for a generated part's true surfaces
#: (:func:`true_part_mesh`): on fresh flange_s7008 (13 facets per circle in its coarse
#: export) the volume of 32k / 63k / 124k triangles is 0.052 / 0.015 / 0.006 % off the exact
#: B-Rep's, the two-sided Hausdorff distance 0.115 / 0.083 / 0.081 % of the diagonal.
TRUE_PART_FACES = 60_000


def true_part_mesh(entry: dict, folder: Path) -> str:
    """A dense tessellation of a generated part's true surfaces (same seed and family, no
    noise, no CAD-export facets, about :data:`TRUE_PART_FACES` triangles), written once to
    ``folder/NAME.true.obj``. A coarse export's own facets are chords of its curved faces
    (a flange with 13 facets per circle: 4.1 % less volume than the part), so an exact B-Rep
    is measured against this instead of against them (``cad_batch_score.py``)."""
    import igl
    import make_parts as mp

    path = folder / f"{entry['name']}.true.obj"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        part = mp.make_part(entry["seed"], entry["family"], target_faces=TRUE_PART_FACES,
                            irregular=0.0, noise=0.0, cad_facets=0)
        igl.write_triangle_mesh(str(path), np.asarray(part.V, np.float64),
                                np.asarray(part.F, np.int64))
    return str(path)


def list_parts(which: str, work: Path) -> list[dict]:
    """Parts as dicts: name, obj, true_faces, triangles, noise, clean (the noise-free mesh of
    a noisy part, else None)."""
    import igl
    import make_parts as mp

    manifest = json.loads((VALIDATION / "manifest.json").read_text())
    out = []
    for p in manifest["parts"]:
        if p["noise"] not in NOISE_LEVELS or (which == "subset" and p["name"] not in SUBSET):
            continue
        out.append(dict(name=p["name"], obj=str(VALIDATION / p["obj"]),
                        true_faces=p["true_faces"], triangles=p["faces"], noise=p["noise"],
                        clean=clean_mesh(p, work / "clean") if p["noise"] else None))
    if which == "subset":
        out.sort(key=lambda p: SUBSET.index(p["name"]))
    abc = work / "abc"
    abc.mkdir(parents=True, exist_ok=True)
    for stem in ABC_PARTS:
        V, F, labels, _ = mp.read_part(ABC_DATA / f"{stem}.obj")
        for noise in (0.0, ABC_NOISE):
            name = f"{stem}_n{noise:g}"
            path = abc / f"{name}.obj"
            if not path.exists():
                W = V if noise == 0 else mp.add_normal_noise(V, F, noise, NOISE_SEED)
                igl.write_triangle_mesh(str(path), W, F)
            out.append(dict(name=name, obj=str(path), true_faces=int(labels.max()) + 1,
                            triangles=int(len(F)), noise=noise,
                            clean=str(abc / f"{stem}_n0.obj") if noise else None))
    return out


#: Budget of surface samples per shape for :func:`sampled_distance`.
SAMPLE_BUDGET = 30_000


def sampled_distance(shape, V, F) -> float:
    """Largest distance from points of the B-Rep's faces to the mesh: each face's surface
    sampled on a grid of its UV bounds, points outside the face dropped (a second B-Rep-to-mesh
    measure beside brep_fidelity's, which uses the shape's tessellation)."""
    import igl
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepClass import BRepClass_FaceClassifier
    from OCP.BRepTools import BRepTools
    from OCP.gp import gp_Pnt2d
    from OCP.TopAbs import TopAbs_IN

    from igl_heatseg.cad.fidelity import faces_of

    faces = faces_of(shape)
    n = int(max(2, min(16, np.sqrt(SAMPLE_BUDGET / max(len(faces), 1)))))
    P = []
    for face in faces:
        surf = BRepAdaptor_Surface(face)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
        cls = BRepClass_FaceClassifier()
        for u in np.linspace(u0, u1, n + 2)[1:-1]:
            for v in np.linspace(v0, v1, n + 2)[1:-1]:
                cls.Perform(face, gp_Pnt2d(float(u), float(v)), 1e-9)
                if cls.State() == TopAbs_IN:
                    q = surf.Value(float(u), float(v))
                    P.append((q.X(), q.Y(), q.Z()))
    if not P:
        return float("nan")
    return float(np.sqrt(igl.point_mesh_squared_distance(np.array(P), V, F)[0]).max())


#: Version of :func:`score`'s measurement; ``--rescore`` scores again the cached results scored
#: by an older one (2: mesh vertices near faces meshed at their loose edges' tolerance get
#: distances to the exact surface, not to its chords; 3: also near faces whose tessellation
#: falls short of their area, where OCC's mesher left a hole).
SCORE_VERSION = 3


def score(step: Path, obj: str, clean: str | None = None) -> dict:
    """brep_fidelity of a STEP file against the mesh (both tools the same way) and, for a
    noisy part, ``clean_hausdorff_rel``: the two-sided Hausdorff distance to the noise-free
    mesh of the same part (how far the B-Rep is from the part itself, not from its noise)."""
    from igl_heatseg.cad import brep_fidelity, read_step
    from igl_heatseg.io import load_mesh

    mesh = load_mesh(obj)
    shape = read_step(step)
    fid = brep_fidelity(shape, mesh.V, mesh.F)
    diag = fid["bbox_diagonal"]
    if clean is not None:
        ref = load_mesh(clean)
        fid["clean_hausdorff_rel"] = brep_fidelity(shape, ref.V, ref.F)["hausdorff_rel"]
    else:
        fid["clean_hausdorff_rel"] = fid["hausdorff_rel"]
    fid["sampled_rel"] = sampled_distance(shape, mesh.V, mesh.F) / diag
    exact = bool(fid["valid"] and fid["solids"] >= 1 and fid["free_edges"] == 0
                 and fid["faces"] < EXACT_FACE_SHARE * len(mesh.F))
    keep = ("valid", "solids", "shells", "faces", "free_edges", "faces_by_type", "hausdorff_rel",
            "sampled_rel",
            "rms", "volume_rel_error", "faces_not_tessellated", "clean_hausdorff_rel")
    return dict({k: fid[k] for k in keep}, exact=exact, triangles=int(len(mesh.F)),
                score_version=SCORE_VERSION)


def run_ours(part: dict, work: Path) -> dict:
    out = work / "ours" / part["name"]
    cmd = [str(Path(sys.executable).parent / "igl-heatseg"), "cad", part["obj"], "-o", str(out),
           "--no-pictures"]
    t = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=OURS_TIMEOUT)
    except subprocess.TimeoutExpired:
        return dict(status="timeout", seconds=OURS_TIMEOUT)
    secs = time.perf_counter() - t
    if p.returncode != 0:
        return dict(status=f"exit {p.returncode}: {p.stderr.strip().splitlines()[-1:]}",
                    seconds=secs)
    rep = json.loads((out / "report.json").read_text())
    res = dict(status="ok", seconds=secs, segments=rep["cad"]["segments"],
               faceted_segments=len(rep["cad"]["not_built"]),
               stage_seconds=rep["cad"]["timings"], total_seconds=rep["timings"]["total"])
    res.update(score(out / "model.step", part["obj"], part["clean"]))
    return res


def run_m2c(part: dict, work: Path, exe: Path) -> dict:
    out = work / "mesh2cad"
    out.mkdir(parents=True, exist_ok=True)
    step = out / f"{part['name']}.step"
    t = time.perf_counter()
    try:
        p = subprocess.run([str(exe), "convert", part["obj"], "-o", str(step)],
                           capture_output=True, text=True, timeout=M2C_TIMEOUT)
    except subprocess.TimeoutExpired:
        return dict(status="timeout", seconds=float(M2C_TIMEOUT))
    secs = time.perf_counter() - t
    if p.returncode != 0 or not step.exists():
        tail = (p.stderr or p.stdout).strip().splitlines()[-1:]
        return dict(status=f"exit {p.returncode}: {tail}", seconds=secs)
    res = dict(status="ok", seconds=secs)
    try:
        res.update(score(step, part["obj"], part["clean"]))
    except Exception as exc:  # an unreadable STEP is a result too
        res.update(status=f"unreadable STEP: {exc}")
    return res


def _cached(work: Path, tool: str, name: str) -> Path:
    d = work / "results" / tool
    d.mkdir(parents=True, exist_ok=True)
    return d / f"{name}.json"


def step_of(work: Path, tool: str, name: str) -> Path:
    return work / "ours" / name / "model.step" if tool == "ours" else \
        work / "mesh2cad" / f"{name}.step"


def _commit() -> str:
    """Short hash of this checkout's HEAD, ``+dirty`` when tracked files are modified."""
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                            "--untracked-files=no"], capture_output=True, text=True).stdout.strip()
    return head + ("+dirty" if dirty else "")


def _stale(tool: str, res: dict, commit: str) -> bool:
    """A cached result of ours from another commit (or from before commits were recorded):
    the table must not print the current commit over it. mesh2cad's do not depend on it."""
    return tool == "ours" and res.get("commit") != commit


def run_queue(tool: str, parts: list[dict], work: Path, fn) -> None:
    """Run ``fn`` on every part without a cached result of this commit (``fn`` None: only
    score again the cached results scored before the distance to the noise-free part existed,
    or by a :data:`SCORE_VERSION` older than this one)."""
    commit = _commit()
    for part in parts:
        path = _cached(work, tool, part["name"])
        if fn is None and not path.exists():
            continue
        if path.exists():
            res = json.loads(path.read_text())
            if fn is not None and _stale(tool, res, commit):
                print(f"{tool:8s} {part['name']:40s} cached at {res.get('commit', '?')}, "
                      f"now {commit}: run again", flush=True)
            else:
                if res["status"] == "ok" and (res.get("score_version", 1) < SCORE_VERSION
                                              or "clean_hausdorff_rel" not in res):
                    res.update(score(step_of(work, tool, part["name"]), part["obj"],
                                     part["clean"]))
                    path.write_text(json.dumps(res, indent=1, default=float) + "\n")
                continue
        start = datetime.datetime.now(datetime.timezone.utc)
        res = fn(part)
        res.update(name=part["name"], commit=commit, started=f"{start:%Y-%m-%d %H:%M:%S}",
                   ended=f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M:%S}")
        path.write_text(json.dumps(res, indent=1, default=float) + "\n")
        print(f"{tool:8s} {part['name']:40s} {res['status']:10s} {res['seconds']:7.1f} s "
              f"exact={res.get('exact')} haus={res.get('hausdorff_rel')}", flush=True)


def _fmt(x, fmt="{:.2f}", none="-"):
    return none if x is None or (isinstance(x, float) and not np.isfinite(x)) else fmt.format(x)


def _sampled(rel) -> str:
    """The sampled B-Rep-to-mesh distance; beyond the part's own size it is a face whose
    trimming the classifier does not bound (an inverted or lost loop), not a distance."""
    if rel is not None and np.isfinite(rel) and rel > 1.0:
        return "unbounded face"
    return _fmt(None if rel is None else 100 * rel, "{:.2f} %")


def _cell(r: dict | None, ours: bool) -> list[str]:
    if r is None:
        return ["not run"] + [""] * (7 if ours else 6)
    if r["status"] != "ok":
        st = "timeout" if r["status"] == "timeout" else "failed"
        return [f"{st} ({r['seconds']:.0f} s)"] + ["-"] * (7 if ours else 6)
    solid = ("valid solid" if r["valid"] and r["solids"] else
             "invalid solid" if r["solids"] else "shell")
    cells = [f"{solid}{', exact' if r['exact'] else ''}", str(r["faces"])]
    if ours:
        cells.append(f"{r['segments']} ({r['faceted_segments']})")
    clean = r.get("clean_hausdorff_rel")
    cells += [_fmt(100 * r["hausdorff_rel"], "{:.2f} %"),
              _fmt(None if clean is None else 100 * clean, "{:.2f} %"),
              _sampled(r.get("sampled_rel")),
              _fmt(None if r["volume_rel_error"] is None else 100 * r["volume_rel_error"],
                   "{:.2f} %"),
              f"{r['seconds']:.0f}"]
    return cells


def write_table(parts: list[dict], work: Path, md: Path, command: str) -> str:
    rows, counts = [], {t: dict(valid=0, exact=0, haus=0, part=0, seconds=0.0, n=0)
                        for t in ("ours", "mesh2cad")}
    loaded: dict = {"ours": [], "mesh2cad": []}
    for p in parts:
        res = {}
        for tool in ("ours", "mesh2cad"):
            path = _cached(work, tool, p["name"])
            res[tool] = json.loads(path.read_text()) if path.exists() else None
            r = res[tool]
            loaded[tool].append(r)
            if r is not None and r["status"] == "ok" and tool == "ours":
                r["exact"] = bool(r["exact"] and r["faceted_segments"] == 0)
            if r is not None:
                c = counts[tool]
                c["n"] += 1
                c["seconds"] += r["seconds"]
                if r["status"] == "ok":
                    c["valid"] += int(bool(r["valid"] and r["solids"] and not r["free_edges"]))
                    c["exact"] += int(r["exact"])
                    c["haus"] += int(r["hausdorff_rel"] <= HAUSDORFF_BAR)
                    part = r.get("clean_hausdorff_rel")  # 0.0 (a faceted model) passes
                    c["part"] += int(part is not None and part <= HAUSDORFF_BAR)
        rows.append(f"| {p['name']} | {p['triangles']} | {p['true_faces']} | "
                    + " | ".join(_cell(res["ours"], True)) + " | "
                    + " | ".join(_cell(res["mesh2cad"], False)) + " |")
    commit = _commit()
    runs = {t: [r for r in loaded[t] if r is not None] for t in loaded}
    ours_commits = sorted({r.get("commit", "unrecorded") for r in runs["ours"]})
    spans = {t: (min(r["started"] for r in rs), max(r["ended"] for r in rs))
             if rs and all("started" in r for r in rs) else None for t, rs in runs.items()}
    if spans["ours"] and spans["mesh2cad"]:
        (a0, a1), (b0, b1) = spans["ours"], spans["mesh2cad"]
        overlap = a0 < b1 and b0 < a1
        how = ("the two tools ran side by side, one process each, so their seconds include "
               "waiting for a core" if overlap else "the two tools ran one after the other")
    else:
        how = "when the tools ran is not recorded for every result"
    span_text = "; ".join(f"{t} {s[0]} to {s[1]} UTC" for t, s in spans.items() if s)
    cpu = next((ln.split(":", 1)[1].strip() for ln in
                Path("/proc/cpuinfo").read_text().splitlines() if ln.startswith("model name")),
               platform.processor())
    ver = work / "m2c-version.txt"
    m2c_version = ver.read_text().strip() if ver.exists() else ""
    lines = [
        "# B-Rep benchmark: `igl-heatseg cad` beside mesh2cad",
        "",
        f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
        f"- commit of this checkout: {commit}; our rows were run at: "
        f"{', '.join(ours_commits) or '-'}",
        f"- machine: {platform.node()}, {cpu}, {os.cpu_count()} cores shared with other jobs "
        f"(load average {os.getloadavg()[0]:.1f} when the table was written); {how}"
        f"{' (' + span_text + ')' if span_text else ''}",
        f"- command: `{command}`",
        f"- ours: `igl-heatseg cad PART.obj -o DIR --no-pictures` (robust mode, default "
        "tolerance 1 % of the bbox diagonal); "
        f"{m2c_version or 'mesh2cad'}: `mesh2cad convert PART.obj -o PART.step` (defaults), "
        f"timeout {M2C_TIMEOUT} s",
        "- both STEP files read back with `read_step` and scored by `brep_fidelity` against "
        "the mesh given to the tool: Hausdorff is `brep_fidelity`'s two-sided distance (mesh "
        "vertices to the B-Rep, B-Rep tessellation vertices to the mesh) over the bbox "
        "diagonal; *samples* is the largest distance from points sampled on every B-Rep face "
        "(a grid over its UV bounds, points outside the face dropped) to the mesh, over the "
        "diagonal: it found B-Rep faces `brep_fidelity` does not see off the mesh (see below); "
        "volume error against "
        "the mesh's volume. *to the part*: the same Hausdorff distance to the noise-free mesh "
        "of a noisy part (same seed and tessellation; the ABC parts' clean copies): how far "
        "the B-Rep is from the part itself rather than from its noise. *exact*: a valid "
        f"closed solid with fewer faces than {EXACT_FACE_SHARE:.0%} of the triangles (a "
        "faceted fallback has about one face per triangle; for ours also no faceted "
        "segment). Segments (faceted): our segments and how many of them became faceted "
        "patches.",
        "",
        "| part | triangles | true faces | ours | faces | segments (faceted) | Hausdorff | "
        "to the part | samples | volume err | s | mesh2cad | faces | Hausdorff | to the part | "
        "samples | volume err | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        f"| tool | parts run | valid closed solids | exact B-Reps | Hausdorff <= "
        f"{HAUSDORFF_BAR:.1%}: to the mesh | to the part | seconds (total) |",
        "|---|---|---|---|---|---|---|",
    ]
    for tool, c in counts.items():
        lines.append(f"| {tool} | {c['n']} | {c['valid']} | {c['exact']} | {c['haus']} | "
                     f"{c['part']} | {c['seconds']:.0f} |")
    text = "\n".join(lines) + "\n"
    md.write_text(text)
    return text


def figures(parts: list[dict], work: Path, names: list[str], outdir: Path) -> None:
    """Re-tessellate two of our STEP files and render them beside their meshes."""
    from igl_heatseg.cad import read_step, tessellate_by_type
    from igl_heatseg.io import load_mesh
    from igl_heatseg.viz import render_brep

    outdir.mkdir(parents=True, exist_ok=True)
    for name in names:
        part = next(p for p in parts if p["name"] == name)
        d = work / "ours" / name
        mesh = load_mesh(part["obj"])
        labels = np.loadtxt(d / "labels.txt", dtype=np.int64)
        if mesh.face_map is not None:  # labels.txt is per input face
            labels = labels[mesh.face_map]
        shape = read_step(d / "model.step")
        diag = float(np.linalg.norm(np.ptp(mesh.V, axis=0)))
        TV, TF, tri_face, types = tessellate_by_type(shape, 1e-3 * diag)
        png = outdir / f"{name}.png"
        render_brep(png, mesh.V, mesh.F, labels, TV, TF, tri_face, types, size=(1000, 440))
        print(f"wrote {png} ({png.stat().st_size // 1024} KB)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", required=True, type=Path, help="work folder (cache, outputs)")
    ap.add_argument("--set", choices=("all", "subset"), default="all")
    ap.add_argument("--m2c-venv", type=Path, default=Path("/work/m2c"))
    ap.add_argument("--tools", nargs="+", default=["ours", "mesh2cad"])
    ap.add_argument("--parts", nargs="+", metavar="NAME", default=None,
                    help="run only these parts, in this order (e.g. a second process on the "
                    "last parts of the list); the table still lists the whole set")
    ap.add_argument("--table", action="store_true", help="only write the table from the cache")
    ap.add_argument("--rescore", action="store_true",
                    help="only score cached results again where the distance to the noise-free "
                    "part is missing or SCORE_VERSION has changed")
    ap.add_argument("--md", type=Path, default=None,
                    help="where the table goes (default WORK/cad_results.md; the file is "
                    "overwritten)")
    ap.add_argument("--figures", nargs="*", metavar="PART", default=None,
                    help="render these parts' STEP files to benchmarks/figures/")
    args = ap.parse_args(argv)
    work = args.work.resolve()
    work.mkdir(parents=True, exist_ok=True)
    parts = list_parts(args.set, work)
    todo = parts if args.parts is None else \
        [next(p for p in parts if p["name"] == n) for n in args.parts]
    if args.rescore:
        for tool in args.tools:
            run_queue(tool, todo, work, None)
    elif not args.table:
        queues = []
        if "mesh2cad" in args.tools:
            exe = ensure_m2c(args.m2c_venv)
            ver = subprocess.run([str(exe), "--version"], capture_output=True, text=True)
            (work / "m2c-version.txt").write_text(ver.stdout.strip() or ver.stderr.strip())
            queues.append(threading.Thread(target=run_queue, args=(
                "mesh2cad", todo, work, lambda p: run_m2c(p, work, exe))))
        if "ours" in args.tools:
            queues.append(threading.Thread(target=run_queue, args=(
                "ours", todo, work, lambda p: run_ours(p, work))))
        for q in queues:
            q.start()
        for q in queues:
            q.join()
    command = "python benchmarks/bench_cad.py " + " ".join(argv if argv is not None
                                                          else sys.argv[1:])
    print(write_table(parts, work, args.md or work / "cad_results.md", command))
    if args.figures:
        figures(parts, work, args.figures, ROOT / "benchmarks" / "figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
