"""What a checkpoint (``io/checkpoints/checkpoint.py``) keeps of the connective tissue
(``coupling/tissue.py``), so that a run whose tissue is cut, torn or attached to a cut organ
resumes bit-identically (issue 41).

Kept (arrays ``tissue.*``): the dissection (``coupling/cutting.py``: which integration points,
attachment points and frames are alive, the (point, frame) pairs severed, the rest-space
triangles cut so far and the events), each attachment's organ cells (a cut organ moves them
to the copies on their side, ``TissueBody.follow_organ_cut``), each blade's last position in
rest space (the next step's sweep continues from it) and the swept triangles in world
coordinates (the pictures show them).

Not kept: the samples, frames, their radii, the material and the cuts' and tearing's set-up,
which the set-up gives; the frame model is made again from the dissection (the same arrays in,
the same model out), after the cut organs are restored (``io/checkpoints/cuts.py``), and the
system with it.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

import numpy as np

from tissuesim.errors import InputError

__all__ = ["capture_tissue", "restore_tissue"]


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"cannot keep {type(obj).__name__} in a checkpoint")


def capture_tissue(sim, arrays: dict) -> dict | None:
    """The tissue's topology and its attachments' cells (arrays into ``arrays``; its
    descriptor, None without a tissue)."""
    tissue = sim.tissue
    if tissue is None:
        return None
    d = tissue.dissection
    arrays["tissue.alive"], arrays["tissue.frame_alive"] = d.alive, d.frame_alive
    arrays["tissue.severed"] = d.severed
    for j, contact in enumerate(tissue.contacts):
        arrays[f"tissue.attachment.{j}.alive"] = d.attachment_alive[j]
        arrays[f"tissue.attachment.{j}.severed"] = d.attachment_severed[j]
        arrays[f"tissue.attachment.{j}.cells"] = contact.cells
    for k, triangles in enumerate(d.cut_triangles):
        arrays[f"tissue.cut_triangles.{k}"] = triangles
    for k, triangles in enumerate(tissue.cut_world):
        arrays[f"tissue.cut_world.{k}"] = triangles
    for name, blade in tissue._rest_blades.items():
        arrays[f"tissue.blade.{name}"] = blade
    return {
        "name": tissue.name,
        "attachments": [c.organ for c in tissue.contacts],
        "cut_triangles": len(d.cut_triangles),
        "cut_world": len(tissue.cut_world),
        "blades": sorted(tissue._rest_blades),
        "events": json.loads(json.dumps(d.events, default=_plain)),
    }


def restore_tissue(sim, meta: dict | None, arrays, path, fix: str) -> None:
    """Put the tissue state ``capture_tissue`` kept into ``sim`` (set up as the run was, its
    cut organs restored, not stepped yet): the dissection and the attachments' cells, then its
    frame model and the system are made anew."""
    tissue = sim.tissue
    if meta is None:
        if tissue is not None:
            raise InputError(f"{path} holds no tissue state (its simulation had none); {fix}")
        return
    d = tissue.dissection if tissue is not None else None
    if (
        tissue is None
        or meta["name"] != tissue.name
        or meta["attachments"] != [c.organ for c in tissue.contacts]
        or np.shape(arrays["tissue.alive"]) != d.alive.shape
        or np.shape(arrays["tissue.frame_alive"]) != d.frame_alive.shape
    ):
        raise InputError(f"{path} holds another tissue than this simulation's; {fix}")
    d.alive = np.array(arrays["tissue.alive"])
    d.frame_alive = np.array(arrays["tissue.frame_alive"])
    d.severed = np.array(arrays["tissue.severed"])
    contacts = []
    for j, contact in enumerate(tissue.contacts):
        alive = np.array(arrays[f"tissue.attachment.{j}.alive"])
        if alive.shape != d.attachment_alive[j].shape:
            raise InputError(f"{path} holds another tissue than this simulation's; {fix}")
        d.attachment_alive[j] = alive
        d.attachment_severed[j] = np.array(arrays[f"tissue.attachment.{j}.severed"])
        cells = np.array(arrays[f"tissue.attachment.{j}.cells"])
        contacts.append(dataclasses.replace(contact, cells=cells))
    tissue.contacts = contacts
    d.cut_triangles = [
        np.array(arrays[f"tissue.cut_triangles.{k}"]) for k in range(meta["cut_triangles"])
    ]
    d.events = list(meta["events"])
    tissue.cut_world = [np.array(arrays[f"tissue.cut_world.{k}"]) for k in range(meta["cut_world"])]
    tissue._rest_blades = {
        name: np.array(arrays[f"tissue.blade.{name}"]) for name in meta["blades"]
    }
    tissue.model = tissue._build_model()
    if tissue.model is not None:
        tissue.config = tissue.model.rest_config()
        tissue.velocity = np.zeros(tissue.model.n_dofs)
    sim._system, sim._state, sim._solver = None, None, None  # the tissue's model anew
    sim._system_dirty = True
