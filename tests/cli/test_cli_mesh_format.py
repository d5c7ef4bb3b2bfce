"""Issue 41: ``tissuesim mesh -o out.xyzzy`` meshed for a minute, then failed naming a
temporary file; the output's format is checked before any meshing."""

from __future__ import annotations

import meshio
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.mesh.from_surface import tetrahedralize as tet


@pytest.fixture
def stl(tmp_path):
    m = ts.ellipsoid(radii=(0.05, 0.03, 0.02), divisions=4)
    path = tmp_path / "organ.stl"
    meshio.write_points_cells(path, m.points, [("triangle", m.facet_sets["surface"])])
    return path


@pytest.mark.parametrize(
    ("name", "said"),
    [("out.xyzzy", "'.xyzzy' is not a mesh format"), ("out.stl", ".stl holds surfaces"),
     ("out", "'' is not a mesh format")],
)  # fmt: skip
def test_an_output_format_that_cannot_hold_tetrahedra_fails_before_meshing(
    name, said, tmp_path, stl, capsys, monkeypatch
):
    def never(*args, **kwargs):
        raise AssertionError("meshed before the output's format was checked")

    monkeypatch.setattr(tet, "tetrahedralize", never)
    out = tmp_path / name
    assert main(["mesh", str(stl), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and str(out) in err and said in err and ".vtu" in err
    assert ".tmp-" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["organ.stl"]
