"""``tissuesim mesh SURFACE -o VOLUME``: writes a readable volume mesh atomically and prints its
quality; bad input is one line and exit code 2."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.cli import main
from tissuesim.mesh.from_surface import meshers

RADII = (0.05, 0.03, 0.02)


@pytest.fixture
def stl(tmp_path):
    m = ts.ellipsoid(radii=RADII, divisions=8)
    path = tmp_path / "organ.stl"
    meshio.write_points_cells(path, m.points, [("triangle", m.facet_sets["surface"])])
    return path


@pytest.mark.skipif(
    "pytetwild" not in meshers.available_meshers(),
    reason="pytetwild (the default mesher, a dependency) is not installed: pip install pytetwild",
)
def test_mesh_writes_a_readable_vtu_and_prints_the_quality(tmp_path, stl, capsys):
    out = tmp_path / "organ.vtu"
    assert main(["mesh", str(stl), "-o", str(out), "--size", "0.01"]) == 0
    summary = json.loads(capsys.readouterr().out)
    mesh = ts.read_mesh(out)
    assert summary["output"] == str(out) and summary["mesher"] == "pytetwild"
    assert summary["n_tets"] == mesh.n_cells > 100 and summary["n_points"] == mesh.n_points
    assert summary["size"] == 0.01 and summary["min_dihedral_deg"] > 5.0
    assert summary["volume"] == pytest.approx(4 / 3 * np.pi * np.prod(RADII), rel=0.03)
    # fTetWild's envelope (0.5 mm here) would allow 5 % (area x envelope / volume); its meshes
    # hold 0.990-1.0 of the volume from run to run (its threads: 0.9899 once under load)
    assert summary["volume_ratio"] == pytest.approx(1.0, abs=0.02)
    assert summary["surface"]["closed"] is True
    assert sorted(p.name for p in tmp_path.iterdir()) == ["organ.stl", "organ.vtu"]  # no temp


def test_mesh_errors_are_one_line_with_exit_code_2(tmp_path, stl, capsys):
    out = tmp_path / "organ.vtu"
    assert main(["mesh", str(tmp_path / "nothing.stl"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nothing.stl: no such surface file" in err
    assert main(["mesh", str(stl), "-o", str(tmp_path / "no" / "dir.vtu")]) == 2
    assert "cannot write the volume mesh there" in capsys.readouterr().err
    assert not out.exists()
    with pytest.raises(SystemExit) as info:
        main(["mesh", str(stl), "-o", str(out), "--size", "-3"])
    assert info.value.code == 2 and "must be a length in metres > 0" in capsys.readouterr().err


def test_mesh_keeps_the_old_file_when_meshing_fails(tmp_path, stl, capsys, monkeypatch):
    from tissuesim.mesh.from_surface import tetrahedralize as tet

    out = tmp_path / "organ.vtu"
    out.write_text("previous mesh")
    monkeypatch.setattr(tet, "available_meshers", lambda: ["pytetwild"])
    monkeypatch.setattr(
        tet, "run_mesher", lambda *a: (np.zeros((4, 3)), np.zeros((0, 4), dtype=np.int64))
    )
    assert main(["mesh", str(stl), "-o", str(out)]) == 2
    assert "produced no tetrahedra" in capsys.readouterr().err
    assert out.read_text() == "previous mesh"


def test_mesh_help_documents_every_option(capsys):
    with pytest.raises(SystemExit):
        main(["mesh", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for option in ("--output", "--size", "--mesher", "metres", "pytetwild"):
        assert option in text


#: a sitecustomize that makes PyVista unimportable, as on a plain install (no [pyvista] extra)
NO_PYVISTA = """
import sys


class _NoPyVista:
    def find_spec(self, name, path=None, target=None):
        if name == "pyvista" or name.startswith("pyvista."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _NoPyVista())
"""


@pytest.mark.skipif(
    "pytetwild" not in meshers.available_meshers(),
    reason="pytetwild (the default mesher, a dependency) is not installed: pip install pytetwild",
)
def test_mesh_works_without_pyvista_as_on_a_plain_install(tmp_path, stl):
    """pytetwild imports PyVista for an accessor that meshing does not use; PyVista is an
    optional extra, so a plain install failed with 'mesher pytetwild is not installed'."""
    import os
    import subprocess
    import sys

    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(NO_PYVISTA)
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")])
    )
    check = [sys.executable, "-c", "import pyvista"]
    assert subprocess.run(check, env=env, capture_output=True).returncode != 0  # hidden
    out = tmp_path / "organ.vtu"
    command = [sys.executable, "-m", "tissuesim", "mesh", str(stl), "-o", str(out)]
    done = subprocess.run([*command, "--size", "0.01"], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert ts.read_mesh(out).n_cells > 100
