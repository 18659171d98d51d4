"""The package's layout rules: imports go down the stages, no cycles, no private imports.

Read from the source (``ast``), so lazy imports inside functions count too.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "igl_heatseg"

#: Stages from the bottom up: a module may import its own stage and any stage listed before it.
STAGES = (
    ("version", "errors", "constants"),
    ("mesh",),
    ("heat",),
    ("surfaces",),
    ("segmentation",),
    ("parameterization",),
    ("cad",),
    ("io",),
    ("pipeline",),
    ("evaluation",),
    ("viz",),
    ("batch",),
    ("cli",),
)
RANK = {name: i for i, names in enumerate(STAGES) for name in names}


def _modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG.parent).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


def _imports(name: str, path: Path, is_pkg: bool):
    """(imported module, imported names, line) for every intra-package import."""
    tree = ast.parse(path.read_text())
    package = name if is_pkg else name.rsplit(".", 1)[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.split(".")[0] == "igl_heatseg":
                yield mod, [a.name for a in node.names], node.lineno
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "igl_heatseg":
                    yield a.name, [], node.lineno


def _stage(mod: str) -> str:
    parts = mod.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_every_module_belongs_to_a_stage():
    unknown = {_stage(m) for m, _, _ in _modules() if _stage(m) and _stage(m) not in RANK}
    assert not unknown - {"__main__", "__init__"}, f"add these to STAGES: {unknown}"


def test_imports_only_go_down_the_stages():
    bad = []
    for name, path, is_pkg in _modules():
        s = _stage(name)
        if s in ("", "__main__"):
            continue
        for mod, _, line in _imports(name, path, is_pkg):
            t = _stage(mod)
            if t and t in RANK and RANK[t] > RANK[s]:
                bad.append(f"{path.relative_to(PKG.parent)}:{line} ({s}) imports {mod} ({t})")
    assert not bad, "\n".join(bad)


def test_no_private_name_imported_from_another_module():
    bad = []
    for name, path, is_pkg in _modules():
        for mod, names, line in _imports(name, path, is_pkg):
            priv = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if priv:
                bad.append(f"{path.relative_to(PKG.parent)}:{line} imports {priv} from {mod}")
    for test in sorted(Path(__file__).parent.glob("test_*.py")):
        for mod, names, line in _imports("tests." + test.stem, test, False):
            priv = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if priv:
                bad.append(f"tests/{test.name}:{line} imports {priv} from {mod}")
    assert not bad, "\n".join(bad)


def test_no_import_cycle_between_modules():
    graph: dict[str, set[str]] = {}
    names = {m for m, _, _ in _modules()}
    for name, path, is_pkg in _modules():
        deps = graph.setdefault(name, set())
        for mod, imported, _ in _imports(name, path, is_pkg):
            # "from pkg import sub" imports the submodule pkg.sub
            targets = [f"{mod}.{n}" for n in imported if f"{mod}.{n}" in names] or [mod]
            deps.update(t for t in targets if t in names and t != name)
    # a package's __init__ re-exporting its own modules is not a cycle of the design
    def edges(a):
        return {b for b in graph.get(a, ()) if not (b.startswith(a + ".") or a.startswith(b + "."))}

    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(a):
        state[a] = 1
        stack.append(a)
        for b in sorted(edges(a)):
            if state.get(b) == 1:
                cycle = stack[stack.index(b):] + [b]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if b not in state:
                visit(b)
        stack.pop()
        state[a] = 2

    for a in sorted(graph):
        if a not in state:
            visit(a)


def test_no_module_over_800_lines():
    long = [
        f"{p.relative_to(PKG.parent)}: {n}"
        for p in sorted(PKG.rglob("*.py"))
        if (n := len(p.read_text().splitlines())) > 800
    ]
    assert not long, "\n".join(long)


def test_import_does_not_load_optional_dependencies():
    code = (
        "import sys, igl_heatseg as ih; "
        "heavy = [m for m in sys.modules if m.split('.')[0] in "
        "('polyscope', 'matplotlib', 'OCP', 'dask', 'distributed', 'gmsh', 'xatlas')]; "
        "print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_top_level_api_reads_like_the_readme():
    import igl_heatseg as ih

    for name in ("load_mesh", "segment", "run", "Segmentation", "HeatSolver", "parameterize_chart",
                 "validate_mesh", "MeshError", "Surface"):
        assert hasattr(ih, name), name
    mesh = ih.load_mesh(Path(__file__).resolve().parents[1] / "data" / "fandisk.off")
    seg = ih.segment(mesh)
    assert isinstance(seg, ih.Segmentation) and seg.num_segments == 15
