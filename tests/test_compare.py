"""Tests for igl_heatseg.evaluation.compare (the ``compare-param`` subcommand module)."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from igl_heatseg.mesh.checks import validate_mesh
from igl_heatseg.cli.compare import register
from igl_heatseg.evaluation.compare import DEFAULT_METHODS, chart_disks, compare_param, format_table
from igl_heatseg.errors import MeshError


def open_box(n=6):
    """Unit cube without its top: five flat sides (sharp edges between them)."""
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    G = np.c_[x.ravel(), y.ravel()]
    idx = np.arange(G.shape[0]).reshape(n + 1, n + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    Fg = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    u, v = G[:, 0], G[:, 1]
    one, zero = np.ones_like(u), np.zeros_like(u)
    sides = [
        np.c_[v, u, zero],  # bottom, normal -z
        np.c_[u, zero, v],  # y = 0, normal -y
        np.c_[one, u, v],  # x = 1, normal +x
        np.c_[v, one, u],  # y = 1, normal +y
        np.c_[zero, v, u],  # x = 0, normal -x
    ]
    V = np.vstack(sides)
    F = np.vstack([Fg + k * len(G) for k in range(5)])
    return validate_mesh(V, F, "open box")


def test_open_box_charts_and_table():
    mesh = open_box()
    rows = compare_param(mesh)
    charts = {r["chart"] for r in rows}
    assert len(charts) == 5
    assert len(rows) == 5 * len(DEFAULT_METHODS)
    for r in rows:
        assert "error" not in r
    hess = [r for r in rows if r["method"].startswith("hessian")]
    # Flat squares: both Hessian maps are exact isometries and bijective.
    assert all(r["bijective"] for r in hess)
    assert all(r["sym_dirichlet"] == pytest.approx(4.0, abs=1e-6) for r in hess)
    text = format_table(rows)
    assert "hessian-hlle" in text and "lscm" in text
    assert len(text.splitlines()) >= len(rows) + 2


def test_chart_disks_are_disks():
    mesh = open_box(4)
    labels = np.repeat(np.arange(5), 2 * 4 * 4)
    charts = chart_disks(mesh, labels)
    assert [c[0] for c in charts] == ["0.0", "1.0", "2.0", "3.0", "4.0"]
    assert all(F.shape[0] == 32 for _, _, F in charts)


def test_pipeline_methods_report_the_resulting_map():
    rows = compare_param(open_box(3), methods=["param-auto"])
    assert len(rows) == 5
    for r in rows:
        assert r["result"] == "hessian-hlle" and r["fallback_used"] is False
    assert "fallback 0/5" in format_table(rows)


def test_unknown_method_raises():
    with pytest.raises(MeshError, match="unknown method"):
        compare_param(open_box(2), methods=["hessian-hlle", "magic"])


def test_register_adds_subcommand(tmp_path, capsys):
    mesh = open_box(3)
    path = tmp_path / "box.obj"
    lines = [f"v {x} {y} {z}" for x, y, z in mesh.V]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.F]
    path.write_text("\n".join(lines) + "\n")
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    register(sub)
    out_json = tmp_path / "rows.json"
    args = parser.parse_args(
        ["compare-param", str(path), "--methods", "hessian-curved,tutte", "--json", str(out_json)]
    )
    assert args.func(args) == 0
    text = capsys.readouterr().out
    assert "hessian-curved" in text and "tutte" in text
    rows = json.loads(out_json.read_text())
    assert {r["method"] for r in rows} == {"hessian-curved", "tutte"}
