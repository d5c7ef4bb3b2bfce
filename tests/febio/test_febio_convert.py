"""Issue 41: ``tissuesim convert`` never writes over its own input or over the scene's own mesh,
and with ``--force`` writes the scene and its mesh as one (both or neither), naming the files
asked for, never a temporary one."""

from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path

import pytest

import tissuesim.io.atomic as atomic
import tissuesim.mesh
from tissuesim.cli import main
from tissuesim.errors import OutputError
from tissuesim.febio import convert_febio

MODEL = Path(__file__).parent / "models" / "uniaxial_neo_hookean.feb"


@pytest.fixture
def model(tmp_path) -> Path:
    feb = tmp_path / "model.feb"
    shutil.copy(MODEL, feb)
    return feb


def test_a_scene_named_like_its_mesh_is_refused(model, tmp_path, capsys):
    assert main(["convert", str(model), str(tmp_path / "scene.msh")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "scene.msh" in err and "scene.toml" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.feb"]


@pytest.mark.parametrize("force", [False, True])
def test_an_output_that_is_the_input_is_refused(model, tmp_path, force, capsys):
    before = model.read_bytes()
    args = ["convert", str(model), str(model)] + ["--force"] * force
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "model.feb" in err and "FEBio model it is converted from" in err
    assert model.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.feb"]


def test_its_mesh_cannot_be_the_input_either(tmp_path):
    feb = tmp_path / "scene.msh"  # a model whose scene's mesh would take its own name
    shutil.copy(MODEL, feb)
    with pytest.raises(OutputError, match="replace the FEBio model"):
        convert_febio(feb, tmp_path / "scene.toml")
    assert feb.read_bytes() == MODEL.read_bytes()


def old_pair(model, tmp_path) -> tuple[Path, dict[str, bytes]]:
    scene = tmp_path / "scene.toml"
    convert_febio(model, scene)
    old = {"scene.toml": b"# old scene\n", "scene.msh": b"old mesh\n"}
    for name, data in old.items():
        (tmp_path / name).write_bytes(data)
    return scene, old


def test_a_failed_mesh_write_with_force_leaves_both_old_files(model, tmp_path, monkeypatch):
    scene, old = old_pair(model, tmp_path)

    def full_disk(mesh, path, **kw):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(tissuesim.mesh, "write_mesh", full_disk)
    with pytest.raises(OutputError) as info:
        convert_febio(model, scene, force=True)
    said = str(info.value)
    assert "scene.toml" in said and "No space left" in said and "nothing was written" in said
    assert ".tmp-" not in said
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name != "model.feb"} == old


def test_a_failed_move_into_place_puts_the_old_pair_back(model, tmp_path, monkeypatch):
    scene, old = old_pair(model, tmp_path)
    replace, failed = os.replace, []

    def fail_on_the_mesh(src, dst):  # the new mesh's move fails, once (the scene's is done)
        if Path(dst).name == "scene.msh" and not failed:
            failed.append(src)
            raise OSError(errno.EIO, os.strerror(errno.EIO), str(src))
        return replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", fail_on_the_mesh)
    with pytest.raises(OutputError, match="nothing was written"):
        convert_febio(model, scene, force=True)
    assert failed
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name != "model.feb"} == old


def test_force_replaces_both(model, tmp_path):
    scene, old = old_pair(model, tmp_path)
    written = convert_febio(model, scene, force=True)
    assert [p.name for p in written] == ["scene.toml", "scene.msh"]
    assert all(p.read_bytes() != old[p.name] for p in written)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.feb", "scene.msh", "scene.toml"]
