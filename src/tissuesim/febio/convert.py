"""``convert``: a FEBio model written as a tissuesim scene (TOML) and its mesh files, all of them
or none."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

from tissuesim.febio.reader import read_feb
from tissuesim.febio.scene import febio_scene
from tissuesim.febio.toml import dumps

__all__ = ["convert_febio"]


def convert_febio(
    path: str | os.PathLike[str],
    scene: str | os.PathLike[str],
    force: bool = False,
    febio_solver: bool = False,
) -> list[Path]:
    """Write the scene ``scene`` (TOML) equivalent to the FEBio model ``path`` and the mesh
    file(s) it references next to it; ``febio_solver``: its steps solved by FEBio's
    quasi-Newton with the first step's <solver> settings (``[newton] method = "febio"``,
    solve/quasin.py), to FEBio's stopping point, not by tissuesim's tight Newton. Refuses to
    overwrite unless ``force``, and refuses
    outright an output that is the model itself or that two outputs share (``scene.msh``
    would be the scene and its own mesh). The scene and its meshes are written as one: all
    of them or, on a failure, none (the old files stay). Returns the paths written."""
    from tissuesim.errors import OutputError
    from tissuesim.io.atomic import atomic_outputs
    from tissuesim.mesh import write_mesh

    scene = Path(scene)
    model = read_feb(path)
    data, meshes = febio_scene(model, scene.stem)
    if febio_solver:
        _use_febio_solver(model, data)
    targets = [scene] + [scene.parent / f for f in meshes]
    if not scene.parent.is_dir():
        raise OutputError(f"{scene}: no directory {scene.parent}")
    source = Path(path).resolve()
    for k, t in enumerate(targets):
        what = "the scene" if k == 0 else "its mesh"
        if t.resolve() == source:
            raise OutputError(
                f"{t}: {what} would replace the FEBio model it is converted from; give the "
                "scene another name (convert MODEL.feb SCENE.toml)"
            )
        if t.is_dir():
            raise OutputError(f"{t}: {what} would be written there, but it is a directory")
    if len({t.resolve() for t in targets}) < len(targets):
        clash = next(t for t in targets[1:] if t.resolve() == scene.resolve())
        raise OutputError(
            f"{clash}: the scene and its mesh would be this one file; give the scene a .toml "
            f"name (e.g. {scene.with_suffix('.toml')})"
        )
    existing = [str(t) for t in targets if t.exists()]
    if existing and not force:
        raise OutputError(f"{existing[0]}: exists; give --force to overwrite it")
    header = [f"converted by tissuesim from the FEBio model {Path(path).name}"]
    header += [f"not used: {n}" for n in model.notes]
    header += [f"changed: {n}" for n in model.changes]
    text = dumps(data, header)
    try:
        with atomic_outputs(targets) as tmps:
            Path(tmps[0]).write_text(text, encoding="utf-8")
            for tmp, mesh in zip(tmps[1:], meshes.values(), strict=True):
                write_mesh(mesh, tmp, file_format="gmsh22")
    except OSError as exc:  # name the file asked for, never the temporary one
        raise OutputError(
            f"{scene}: cannot write the scene and its mesh ({exc.strerror or exc}); nothing "
            "was written"
        ) from None
    for line in model.changes:  # one warning line each (run prints them too: load_febio)
        warnings.warn(f"changed: {line}", UserWarning, stacklevel=2)
    return targets


def _use_febio_solver(model, data: dict) -> None:
    """[newton] method = "febio" with the first step's <solver> settings (checked here, so a
    bad one is refused in one line naming the model); its "not used" note dropped."""
    from tissuesim.errors import InputError
    from tissuesim.solve.febio_settings import FebioSettings

    settings = dict(model.febio_solver or {})
    try:
        FebioSettings.from_table(settings)
    except InputError as exc:
        raise InputError(f"{model.source}: the first step's <solver>: {exc}") from None
    newton = data.setdefault("newton", {})
    newton["method"] = "febio"
    if settings:
        newton["febio"] = settings
    if model.febio_solver_note is not None:
        del model.notes[model.febio_solver_note]
        model.febio_solver_note = None
