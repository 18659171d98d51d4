"""Every shipped data file is credited, and every mesh loads."""

from igl_heatseg.io.meshes import SUPPORTED_EXTENSIONS, load_mesh


def _files(data_dir):
    return sorted(p for p in data_dir.iterdir() if p.name != "CREDITS.md")


def test_every_data_file_is_credited(data_dir):
    credits = (data_dir / "CREDITS.md").read_text()
    for p in _files(data_dir):
        assert f"| {p.name} |" in credits, f"{p.name} has no line in data/CREDITS.md"


def test_data_files_are_small(data_dir):
    for p in _files(data_dir):
        assert p.stat().st_size < 600_000, p.name


def test_every_mesh_loads(data_dir):
    meshes = [p for p in _files(data_dir) if p.suffix in SUPPORTED_EXTENSIONS]
    assert len(meshes) >= 4
    for p in meshes:
        m = load_mesh(p)
        # (the generated coarse housings: 716 and 1,364; the generated nut: 5,810; public
        # copies: > 14k)
        assert m.F.shape[0] > 500
