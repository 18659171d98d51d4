"""``igl-heatseg batch`` and :func:`igl_heatseg.batch.run_batch` on Dask.

A folder of 20 small generated meshes: 16 good, 3 bad files, 1 that sleeps past a 2-second
timeout (through the job server's test hook). One LocalCluster of 2 single-threaded workers
serves the in-process tests; one test kills a batch subprocess half-way; one runs against a
scheduler and a worker the test starts on 127.0.0.1.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import igl
import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from igl_heatseg.batch import (  # noqa: E402
    JOB_KINDS,
    discover,
    parse_memory,
    process_mesh,
    run_batch,
)
from igl_heatseg.batch.server import TEST_ALLOCATE_ENV, TEST_SLEEP_ENV  # noqa: E402
from igl_heatseg.batch.worker import TEST_KILL_ENV, stop_servers  # noqa: E402
from igl_heatseg.cli import main  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
GOOD, BAD, SLOW = 16, 3, 1


def _sphere(level, scale=(1.0, 1.0, 1.0)):
    V, F = igl.icosahedron()
    V, F = igl.loop(V, F, level)
    V = V / np.linalg.norm(V, axis=1, keepdims=True)
    return V * np.asarray(scale), F


def _box(level, size=(1.0, 1.0, 1.0)):
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    F = np.array(
        [
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ]
    )
    if level:
        V, F = igl.upsample(V, F, level)
    return V * np.asarray(size), F


def _cylinder(n=24, rings=4, r=1.0, h=2.0):
    t = 2 * np.pi * np.arange(n) / n
    V = [[r * np.cos(a), r * np.sin(a), z] for z in np.linspace(0, h, rings + 1) for a in t]
    F = []
    for i in range(rings):
        for j in range(n):
            a, b = i * n + j, i * n + (j + 1) % n
            F += [[a, b, b + n], [a, b + n, a + n]]
    bottom, top = len(V), len(V) + 1
    V += [[0, 0, 0], [0, 0, h]]
    for j in range(n):
        F.append([bottom, (j + 1) % n, j])
        F.append([top, rings * n + j, rings * n + (j + 1) % n])
    return np.array(V, float), np.array(F)


def make_meshes(root: Path) -> dict:
    """20 meshes in subfolders: 16 good (OBJ, OFF, PLY, STL), 3 bad, 1 slow."""
    good = [
        ("spheres/s2.obj", _sphere(2)), ("spheres/s3.off", _sphere(3)),
        ("spheres/ell2.ply", _sphere(2, (2, 1, 1))), ("spheres/ell3.obj", _sphere(3, (1, 2, 3))),
        ("spheres/big.stl", _sphere(2, (5, 5, 5))), ("spheres/flat.obj", _sphere(2, (3, 3, 1))),
        ("boxes/b0.obj", _box(1)), ("boxes/b1.off", _box(2)), ("boxes/b2.ply", _box(3)),
        ("boxes/slab.obj", _box(2, (4, 2, 0.5))), ("boxes/bar.stl", _box(2, (5, 1, 1))),
        ("boxes/cube.obj", _box(3, (2, 2, 2))),
        ("cylinders/c1.obj", _cylinder()), ("cylinders/c2.off", _cylinder(32, 6)),
        ("cylinders/thin.ply", _cylinder(16, 8, 0.3, 4)),
        ("cylinders/disc.obj", _cylinder(40, 1, 3, 0.5)),
    ]  # fmt: skip
    for name, (V, F) in good + [("slow/slow_sphere.obj", _sphere(2))]:
        p = root / name
        p.parent.mkdir(parents=True, exist_ok=True)
        igl.write_triangle_mesh(str(p), V, np.asarray(F, dtype=np.int64))
    (root / "bad").mkdir()
    (root / "bad/garbage.obj").write_text("this is not a mesh\n")
    (root / "bad/empty.off").write_text("OFF\n0 0 0\n")
    (root / "bad/out_of_range.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    return {"good": [n for n, _ in good]}


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    root = tmp_path_factory.mktemp("meshes")
    info = make_meshes(root)
    return root, info


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    """A LocalCluster of 2 single-threaded workers whose environment carries the test hooks:
    ``slow_*`` sleeps 30 s; ``killer*`` kills its worker the first time."""
    marks = tmp_path_factory.mktemp("kill-marks")
    env = {TEST_SLEEP_ENV: "slow_*=30", TEST_KILL_ENV: f"killer*={marks}"}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    import dask

    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
            cluster = distributed.LocalCluster(
                n_workers=2,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                host="127.0.0.1",
            )
        c = distributed.Client(cluster)
        yield c
        c.close()
        cluster.close()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _by_mesh(res):
    return {r["mesh"]: r for r in res.records}


def test_discover_files_folders_patterns(meshes, tmp_path):
    root, _ = meshes
    found = discover([root])
    assert len(found) == 20
    assert {m.key for m in found} >= {"spheres/s2", "boxes/b1", "bad/garbage", "slow/slow_sphere"}
    pat = discover([str(root / "boxes" / "*.obj"), root / "spheres" / "s3.off"])
    assert [(m.name, m.key) for m in pat] == [
        ("b0.obj", "b0"),
        ("cube.obj", "cube"),
        ("slab.obj", "slab"),
        ("s3.off", "s3"),
    ]
    assert len(discover([str(root / "**" / "*.stl")])) == 2
    # the same file twice is one mesh; OUT inside an input folder is not searched
    assert len(discover([root, root / "boxes" / "b0.obj"], exclude=root / "boxes")) == 14
    (tmp_path / "a.obj").write_text("")
    (tmp_path / "a.stl").write_text("")
    assert sorted(m.key for m in discover([tmp_path])) == ["a.obj", "a.stl"]
    with pytest.raises(ValueError, match="no such file"):
        discover([tmp_path / "missing"])
    with pytest.raises(ValueError, match="matches no mesh"):
        discover([str(tmp_path / "*.off")])


def test_parse_memory_and_job_kinds():
    assert parse_memory("4GB") == 4 * 10**9 and parse_memory("512MiB") == 512 * 2**20
    assert parse_memory("none") is None and parse_memory(0) is None
    with pytest.raises(ValueError):
        parse_memory("lots")
    assert {"segment", "run"} <= set(JOB_KINDS)


def test_job_outside_dask_writes_what_the_command_writes(meshes, tmp_path):
    """process_mesh (the task) and `igl-heatseg segment`/`run` write the same files."""
    root, _ = meshes
    mesh = root / "boxes" / "b1.off"
    for command in ("segment", "run"):
        a, b = tmp_path / f"task-{command}", tmp_path / f"cli-{command}"
        rec = process_mesh(
            {
                "mesh": "b1.off",
                "input": str(mesh),
                "output": str(a),
                "kind": command,
                "options": {"pictures": False},
                "timeout": 60,
            }
        )
        assert rec["status"] == "done", rec
        argv = [command, str(mesh), "-o", str(b)] + (["--no-pictures"] if command == "run" else [])
        assert main(argv) == 0
        files = sorted(p.relative_to(a).as_posix() for p in a.rglob("*"))
        assert files == sorted(p.relative_to(b).as_posix() for p in b.rglob("*"))
        for f in ("labels.txt", "vertex_labels.txt", "segmented.ply"):
            assert (a / f).read_bytes() == (b / f).read_bytes()
        ra, rb = (
            json.loads((a / "report.json").read_text()),
            json.loads((b / "report.json").read_text()),
        )
        assert ra.keys() == rb.keys() and ra["segments"] == rb["segments"] == rec["segments"]
        assert rec["peak_memory_mb"] > 10
    assert rec["charts"] == rec["bijective"] and rec["fallback"] is not None


def test_a_cad_job_gets_a_share_of_its_timeout_as_its_time_limit(monkeypatch, tmp_path):
    """The job server gives a kind that takes a time limit (cad) TIME_LIMIT_SHARE of the
    timeout, unless the batch gives one or has no timeout; other kinds get none."""
    from dataclasses import replace

    from igl_heatseg.batch import jobs
    from igl_heatseg.batch.server import TIME_LIMIT_SHARE, child_job

    seen = []
    for name in ("cad", "segment"):
        fake = replace(jobs.JOB_KINDS[name], summarize=lambda report: {},
                       run=lambda mesh, out, **opts: seen.append(opts) or {})
        monkeypatch.setitem(jobs.JOB_KINDS, name, fake)
    req = {"kind": "cad", "mesh": "m.off", "out": str(tmp_path / "o"),
           "options": {"mode": "robust", "energy": "hlle"}}
    for extra in ({"timeout": 600}, {"timeout": None},
                  {"timeout": 600, "options": {"time_limit": 60}},
                  {"timeout": 600, "kind": "segment"}):
        assert child_job(dict(req, **extra))["status"] == "done"
    assert TIME_LIMIT_SHARE == 0.5
    assert seen == [{"mode": "robust", "time_limit": 300.0}, {"mode": "robust"},
                    {"time_limit": 60}, {"mode": "robust"}]


def test_cad_rows_give_the_brep_and_a_skipped_row_keeps_its_reason(tmp_path):
    """A cad job's summary row: the B-Rep's kind, faceted segments, distances, and the build's
    message as its reason (what the time limit skipped); a skipped row keeps its own reason;
    the CSV has the columns and the gallery card the numbers."""
    from igl_heatseg.batch.summary import COLUMNS, skipped_record, write_gallery, write_summary

    report = {"faces": 900, "segments": 30, "timings": {"total": 12.5},
              "cad": {"not_built": [3, 7], "faceted_model": False,
                      "message": "closed mesh but the shell is open; time limit reached: "
                                 "skipped rebuild 1 (segments [3] faceted)",
                      "fidelity": {"valid": True, "solids": 0, "shells": 2,
                                   "hausdorff_rel": 0.0079, "volume_rel_error": None}}}
    row = JOB_KINDS["cad"].summarize(report)
    assert row["brep"] == "2 shells" and row["faceted"] == 2
    assert row["hausdorff_pct"] == 0.79 and row["volume_error_pct"] is None
    assert "time limit reached" in row["reason"]
    folder = tmp_path / "part"
    folder.mkdir()
    (folder / "report.json").write_text(json.dumps(report))
    skipped = skipped_record("part.obj", "part.obj", str(folder), JOB_KINDS["cad"].summarize)
    assert skipped["reason"].startswith("complete output found") and skipped["faceted"] == 2
    assert skipped["seconds"] == 12.5
    assert {"brep", "faceted", "hausdorff_pct", "volume_error_pct"} <= set(COLUMNS)
    done = dict(row, mesh="part.obj", status="done", output=str(folder), seconds=12.5)
    write_summary(tmp_path, [done], {})
    rows = list(csv.DictReader((tmp_path / "summary.csv").open()))
    assert rows[0]["brep"] == "2 shells" and float(rows[0]["hausdorff_pct"]) == 0.79
    assert "brep 2 shells, faceted 2" in write_gallery(tmp_path, [done]).read_text()
    faceted = dict(report["cad"], faceted_model=True,
                   fidelity={"valid": False, "solids": 1, "shells": 1})
    assert JOB_KINDS["cad"].summarize(dict(report, cad=faceted))["brep"] == (
        "faceted solid (invalid)")
    mixed = dict(report["cad"], fidelity={"valid": True, "solids": 1, "shells": 3})
    assert JOB_KINDS["cad"].summarize(dict(report, cad=mixed))["brep"] == "3 shells (1 solids)"
    assert JOB_KINDS["segment"].summarize(report).get("brep") is None


def test_timeout_and_memory_limit_in_the_job(meshes, tmp_path):
    root, _ = meshes
    mesh = str(root / "spheres" / "s3.off")
    task = {"mesh": "s3.off", "input": mesh, "kind": "segment"}
    stop_servers()  # a job server keeps the environment it was started with
    os.environ[TEST_SLEEP_ENV] = "s3.off=30"
    try:
        t = time.perf_counter()
        rec = process_mesh(dict(task, output=str(tmp_path / "t"), timeout=1.0))
        assert time.perf_counter() - t < 20
        assert rec["status"] == "timeout" and "1 s timeout" in rec["reason"], rec
        # a job that needs 2 GB under a 1 GB limit is recorded, not the worker lost
        stop_servers()
        os.environ[TEST_SLEEP_ENV] = ""
        os.environ[TEST_ALLOCATE_ENV] = "s3.off=2000000000"
        rec = process_mesh(
            dict(task, output=str(tmp_path / "m"), timeout=30, memory_limit=10**9,
                 memory_limit_text="1GB")
        )  # fmt: skip
        assert rec["status"] == "memory" and "limit 1GB" in rec["reason"], rec
    finally:
        os.environ.pop(TEST_SLEEP_ENV, None)
        os.environ.pop(TEST_ALLOCATE_ENV, None)
        stop_servers()
    assert not (tmp_path / "t").exists() and not (tmp_path / "m").exists()


def test_batch_records_failures_then_skips_what_is_complete(meshes, client, tmp_path):
    root, info = meshes
    out = tmp_path / "out"
    res = run_batch([root], out, client=client, timeout=2.0, progress=False)
    c = res.counts
    assert (c.get("done"), c.get("rejected"), c.get("timeout"), c["total"]) == (16, 3, 1, 20), c
    by = _by_mesh(res)
    for name in info["good"]:
        r = by[name]
        assert r["status"] == "done" and r["faces"] > 0 and r["segments"] >= 1, r
        assert (Path(r["output"]) / "report.json").is_file()
    assert "no 'v' or 'f' lines" in by["bad/garbage.obj"]["reason"]
    assert "no faces" in by["bad/empty.off"]["reason"]
    assert "refers to no vertex" in by["bad/out_of_range.obj"]["reason"]
    assert by["slow/slow_sphere.obj"]["reason"].startswith("exceeded the 2 s timeout")
    assert not (out / "slow" / "slow_sphere").exists() and not (out / "bad" / "garbage").exists()
    # the summary
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert len(rows) == 20 and set(rows[0]) >= {
        "mesh",
        "status",
        "reason",
        "faces",
        "segments",
        "charts",
        "bijective",
        "fallback",
        "seconds",
        "peak_memory_mb",
    }
    doc = json.loads((out / "summary.json").read_text())
    assert doc["counts"]["done"] == 16 and doc["finished"] and len(doc["meshes"]) == 20
    html = (out / "index.html").read_text()
    assert html.index("slow/slow_sphere.obj") < html.index("spheres/s2.obj")  # failures on top
    stamp = {n: (out / by[n]["output"] / "report.json").stat().st_mtime_ns for n in info["good"]}
    # a batch killed while writing its summary leaves its temporary files: the next run
    # removes them
    stale = [out / f".{name}.999999.tmp" for name in ("summary.json", "index.html")]
    for p in stale:
        p.write_text("partial")
    # second run: the 16 are skipped, only the 4 failures are tried again
    res2 = run_batch([root], out, client=client, timeout=2.0, progress=False)
    assert not any(p.exists() for p in stale)
    c2 = res2.counts
    assert (c2.get("skipped"), c2.get("rejected"), c2.get("timeout")) == (16, 3, 1), c2
    assert all(
        (out / _by_mesh(res2)[n]["output"] / "report.json").stat().st_mtime_ns == stamp[n]
        for n in info["good"]
    )
    assert _by_mesh(res2)["boxes/b2.ply"]["faces"] == by["boxes/b2.ply"]["faces"]
    # --force redoes one
    res3 = run_batch([root / "boxes" / "b0.obj"], out, client=client, force=True, progress=False)
    assert res3.counts == {"done": 1, "total": 1}


def test_dead_worker_is_replaced_and_its_mesh_retried(meshes, client, tmp_path):
    root, _ = meshes
    src = tmp_path / "in"
    src.mkdir()
    V, F = _sphere(2)
    igl.write_triangle_mesh(str(src / "killer.obj"), V, F)
    igl.write_triangle_mesh(str(src / "other.obj"), *_box(1))
    res = run_batch([src], tmp_path / "out", client=client, timeout=30, progress=False)
    assert res.counts.get("done") == 2, res.records
    client.wait_for_workers(2, timeout=60)


def _count_complete(out: Path) -> list[Path]:
    """Complete output folders (os.walk: a folder renamed while it looks is skipped, where
    Path.rglob raises)."""
    return [Path(root) for root, _, files in os.walk(out) if "report.json" in files]


def test_killed_batch_restarts_and_loses_nothing(meshes, client, tmp_path):
    root, info = meshes
    out = tmp_path / "out"
    env = dict(os.environ)
    env[TEST_SLEEP_ENV] = "slow_*=30,*=0.5"  # every mesh takes > 0.5 s: time to kill half-way
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in [env.get("PYTHONPATH")] if p])
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "igl_heatseg",
            "batch",
            str(root),
            "-o",
            str(out),
            "--workers",
            "2",
            "--timeout",
            "2",
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        while len(_count_complete(out)) < 4 and time.monotonic() < deadline:
            assert proc.poll() is None, "the batch ended before it could be killed"
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the batch, its cluster, its jobs
        proc.wait()
    before = {p: (p / "report.json").stat().st_mtime_ns for p in _count_complete(out)}
    assert 4 <= len(before) < 16
    time.sleep(0.5)  # a job child dies with its server (PR_SET_PDEATHSIG)
    # every folder that looks complete is complete
    for p in before:
        assert {"labels.txt", "vertex_labels.txt", "segmented.ply"} <= {f.name for f in p.iterdir()}
    res = run_batch([root], out, client=client, timeout=2.0, progress=False)
    c = res.counts
    assert c.get("skipped") == len(before) and c.get("done") == 16 - len(before), c
    assert (c.get("rejected"), c.get("timeout")) == (3, 1)
    for p, stamp in before.items():
        assert (p / "report.json").stat().st_mtime_ns == stamp
    assert not [p for p in out.rglob(".*.tmp")], "temporary folders left behind"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_batch_on_a_scheduler_the_test_starts(meshes, tmp_path):
    root, _ = meshes
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in [env.get("PYTHONPATH")] if p])
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "dask",
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--no-dashboard",
            ],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        procs.append(
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "dask",
                    "worker",
                    addr,
                    "--host",
                    "127.0.0.1",
                    "--nthreads",
                    "1",
                    "--nworkers",
                    "1",
                    "--no-dashboard",
                ],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        out = tmp_path / "out"
        argv = [
            "batch",
            str(root / "boxes" / "*.obj"),
            str(root / "bad" / "empty.off"),
            "-o",
            str(out),
            "--scheduler",
            addr,
            "--timeout",
            "30",
        ]
        assert main(argv) == 1  # one mesh failed
        rows = {r["mesh"]: r for r in csv.DictReader((out / "summary.csv").open())}
        assert len(rows) == 4
        assert [r["status"] for r in rows.values()].count("done") == 3
        assert rows["empty.off"]["status"] == "rejected"
        assert (out / "slab" / "report.json").is_file() and (out / "index.html").is_file()
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def test_batch_mode_defaults_to_the_commands_own(meshes, client, tmp_path):
    """`batch --command cad` segments in robust mode, as `igl-heatseg cad` does (it used paper
    mode: 502 faceted segments on a pipe elbow that robust mode gives 10); segment keeps paper
    mode. The mode used is recorded in summary.json and in each report."""
    pytest.importorskip("OCP")
    root, _ = meshes
    box = root / "boxes" / "b1.off"
    for command, mode in (("segment", "paper"), ("cad", "robust")):
        out = tmp_path / command
        res = run_batch([box], out, command=command, client=client, pictures=False,
                        progress=False)
        assert not res.failed
        assert json.loads((out / "summary.json").read_text())["options"]["mode"] == mode
        (report,) = out.rglob("report.json")
        assert json.loads(report.read_text())["mode"] == mode


def test_cli_batch_is_registered_and_reports_bad_arguments(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "missing"), "-o", str(tmp_path / "o")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["batch", str(tmp_path), "-o", str(tmp_path / "o"), "--memory-limit", "x"]) == 2
