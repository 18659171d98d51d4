"""Execute every notebook in notebooks/ end to end (outputs are not written back).

The viewer is switched to a headless backend through ``IGL_HEATSEG_PS_BACKEND``: EGL when an
EGL library can be loaded (so the pictures are real), polyscope's mock backend otherwise.
"""

from __future__ import annotations

import ctypes
import json
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("polyscope")

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))

#: Seconds one cell may run.
CELL_TIMEOUT = 300


def _egl_loadable() -> bool:
    for name in ("libEGL.so.1", "libEGL.so"):
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def test_notebooks_exist_and_are_stripped():
    names = [p.name for p in NOTEBOOKS]
    assert names == ["01_pipeline_fandisk.ipynb", "02_paper_tables.ipynb", "03_sensitivity.ipynb"]
    for p in NOTEBOOKS:
        raw = json.loads(p.read_text())
        nb = nbformat.reads(p.read_text(), as_version=4)
        nbformat.validate(nb)
        for cell in raw["cells"]:
            if cell["cell_type"] == "code":
                assert cell["outputs"] == [] and cell["execution_count"] is None, p.name


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path, monkeypatch):
    monkeypatch.setenv("IGL_HEATSEG_ROOT", str(ROOT))
    monkeypatch.setenv("IGL_HEATSEG_NB_OUT", str(tmp_path))
    monkeypatch.setenv(
        "IGL_HEATSEG_PS_BACKEND", "openGL3_egl" if _egl_loadable() else "openGL_mock"
    )
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        timeout=CELL_TIMEOUT,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )
    client.execute()
    errors = [
        o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"
    ]
    assert not errors
    if path.name.startswith("01"):
        pngs = {p.name for p in tmp_path.glob("*.png")}
        for stage in ("seeds", "temperature", "initial", "final", "types", "checker", "charts"):
            assert f"fandisk_{stage}.png" in pngs
