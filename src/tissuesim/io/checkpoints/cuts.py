"""What a checkpoint (``io/checkpoints/checkpoint.py``) keeps of cut and torn FEM bodies, so that a
run that cuts or tears resumes bit-identically (issue 41).

Kept, per cut body (arrays ``cut.<body>.*``): its current cut mesh (``VirtualNodeMesh``: the
points, cells, volume fractions, parents, sides, cuts and origins, each copy's levels and the
rows of the further cuts and shaves of cells several cuts cross), its cuts so far (a plane
bounded by its polygon, or the triangles of a swept surface) and their names, the copy each
copy continues (``source``, from which the next cut renews the sparsity pattern), the areas
credited so far (faces a cut parted, the sections measured per cut), the vertices each
support and grasper holds now (by name) and the body's velocity. Per blade (``blade.<name>.*``):
its plane, whether it has left it, its samples so far and when it was last sampled, the area
it has cut and whether it is out of contact with its body for the next step. Per tearing
body (``tear.<body>.<k>.*``): each crack's current plane and polygon, its earlier pieces and
the front it turned at.

Not kept: the original mesh, the cells' densities and rest geometry, which the set-up gives
(the fingerprint checks the original mesh, ``io/checkpoints/fingerprint.py``); the model, its
pattern, the contact surface and the crumbs' attachment are made again from the cut mesh (the
same arrays in, the same bits out: a pattern renewed after a cut equals the one built afresh
entry for entry). The linear solver's state, the contact state and the step history are the
checkpoint's own, as for any run.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tissuesim.errors import InputError

__all__ = ["capture_cuts", "restore_cuts"]

_VN = ("points", "cells", "fraction", "parent", "side", "cut", "origin")
_ROWS = ("copy", "cut", "side", "level")


def _put_cut(arrays: dict, key: str, cut) -> str:
    """Keep a ``PlanarCut`` or ``SweptCut`` under ``key``; returns its kind."""
    from tissuesim.mesh.cutting.swept_cut import SweptCut

    if isinstance(cut, SweptCut):
        arrays[f"{key}.triangles"] = cut.triangles
        return "swept"
    arrays[f"{key}.point"], arrays[f"{key}.normal"] = cut.point, cut.normal
    arrays[f"{key}.polygon"] = cut.polygon
    return "planar"


def _get_cut(arrays, key: str, kind: str):
    from tissuesim.mesh.cutting.swept_cut import SweptCut
    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    if kind == "swept":
        return SweptCut(np.array(arrays[f"{key}.triangles"]))
    return PlanarCut(*(np.array(arrays[f"{key}.{k}"]) for k in ("point", "normal", "polygon")))


def _optional(arrays, key: str) -> np.ndarray | None:
    return np.array(arrays[key]) if key in arrays else None


# -- a cut body -------------------------------------------------------------------------------
def _put_body(arrays: dict, key: str, b) -> dict:
    state, vn = b.cut_state, b.cut_state.vn
    meta: dict[str, Any] = {"cut": vn is not None}
    if vn is None:  # cut_state made, nothing cut yet
        return meta
    for f in _VN:
        arrays[f"{key}.vn.{f}"] = getattr(vn, f)
    if vn.level is not None:
        arrays[f"{key}.vn.level"] = vn.level
    for which in ("extra", "shave"):
        rows = getattr(vn, which)
        if rows is not None:
            for f, a in zip(_ROWS, rows.rows(), strict=True):
                arrays[f"{key}.{which}.{f}"] = a
    meta["names"] = list(state.names)
    meta["cuts"] = [_put_cut(arrays, f"{key}.cuts.{k}", c) for k, c in enumerate(state.cuts)]
    if state.source is not None:
        arrays[f"{key}.source"] = state.source
    arrays[f"{key}.face_area"] = np.asarray(state.face_area, dtype=float)
    if state._parted is not None:
        arrays[f"{key}.parted"] = state._parted
    meta["sections"] = sorted(int(j) for j in (state._sections or {}))
    for j in meta["sections"]:
        arrays[f"{key}.sections.{j}"] = state._sections[j]
    held = {name: c.vertices for name, c in b.conditions}
    held.update({g.name: g.vertices for g in b.graspers})
    meta["held"] = sorted(held)
    for k, name in enumerate(meta["held"]):
        arrays[f"{key}.held.{k}"] = held[name]
    arrays[f"{key}.velocity"] = b.velocity
    return meta


def _get_body(sim, name: str, meta: dict, arrays, key: str, path) -> None:
    from tissuesim.bodies.cut_state import CutState
    from tissuesim.mesh.cutting.virtual_nodes import Constraints, VirtualNodeMesh

    b = sim.bodies.get(name)
    if b is None or b.kind != "fem":
        raise InputError(f"{path} holds the cut of a FEM body {name!r} this simulation lacks")
    was = b.cut_state  # cut already by the set-up (cut_body before the run): its original
    if was is None:
        state = CutState.of_model(b.model)
    else:
        state = CutState(was.original, was.density, was.rest)
    if not meta["cut"]:
        b.cut_state = state
        return
    rows = {}
    for which in ("extra", "shave"):
        if f"{key}.{which}.copy" in arrays:
            rows[which] = Constraints(*(np.array(arrays[f"{key}.{which}.{f}"]) for f in _ROWS))
    state.vn = VirtualNodeMesh(
        *(np.array(arrays[f"{key}.vn.{f}"]) for f in _VN),
        level=_optional(arrays, f"{key}.vn.level"),
        **rows,
    )
    state.names = list(meta["names"])
    state.cuts = [_get_cut(arrays, f"{key}.cuts.{k}", kind) for k, kind in enumerate(meta["cuts"])]
    state.source = _optional(arrays, f"{key}.source")
    state.face_area = [float(a) for a in arrays[f"{key}.face_area"]]
    state._parted = _optional(arrays, f"{key}.parted")
    state._sections = {j: np.array(arrays[f"{key}.sections.{j}"]) for j in meta["sections"]}
    held = {n: np.array(arrays[f"{key}.held.{k}"]) for k, n in enumerate(meta["held"])}
    have = {n for n, _ in b.conditions} | {g.name for g in b.graspers}
    if have != set(held):
        raise InputError(
            f"{path} holds the supports and graspers {sorted(held)} of body {name!r}, this "
            f"simulation has {sorted(have)}; set it up as the run was"
        )
    b.restore_cut(state, held, np.array(arrays[f"{key}.velocity"]))


# -- blades and tearing -----------------------------------------------------------------------
def _put_blade(arrays: dict, key: str, blade) -> dict:
    for f in ("point", "normal"):
        if getattr(blade, f) is not None:
            arrays[f"{key}.{f}"] = getattr(blade, f)
    samples = [np.asarray(s) for s in blade._samples]
    arrays[f"{key}.samples"] = np.concatenate(samples) if samples else np.zeros((0, 3))
    arrays[f"{key}.sample_sizes"] = np.array([len(s) for s in samples], dtype=np.int64)
    arrays[f"{key}.numbers"] = np.array([blade.area, blade._sampled_to])
    return {"curved": bool(blade.curved), "suspended": bool(blade.suspended)}


def _get_blade(blade, meta: dict, arrays, key: str) -> None:
    blade.point = _optional(arrays, f"{key}.point")
    blade.normal = _optional(arrays, f"{key}.normal")
    sizes = np.array(arrays[f"{key}.sample_sizes"])
    blade._samples = np.split(np.array(arrays[f"{key}.samples"]), np.cumsum(sizes)[:-1])
    if not len(sizes):
        blade._samples = []
    area, sampled_to = (float(a) for a in arrays[f"{key}.numbers"])
    blade.area, blade._sampled_to = area, sampled_to
    blade.curved, blade.suspended = meta["curved"], meta["suspended"]
    blade.pending, blade.path = None, None  # a step's own: made again before the next


def _put_tear(arrays: dict, key: str, tear) -> list:
    out = []
    for k, crack in enumerate(tear.cracks):
        at = f"{key}.{k}"
        arrays[f"{at}.point"], arrays[f"{at}.normal"] = crack.point, crack.normal
        for f in ("corners", "_front", "_growth"):
            if getattr(crack, f) is not None:
                arrays[f"{at}.{f.strip('_')}"] = getattr(crack, f)
        for j, piece in enumerate(crack.pieces):
            _put_cut(arrays, f"{at}.pieces.{j}", piece)
        out.append({"name": crack.name, "pieces": len(crack.pieces)})
    return out


def _get_tear(tear, meta: list, arrays, key: str) -> None:
    from tissuesim.bodies.organ_tear import Crack

    tear.cracks = []
    for k, m in enumerate(meta):
        at = f"{key}.{k}"
        crack = Crack(
            m["name"],
            np.array(arrays[f"{at}.point"]),
            np.array(arrays[f"{at}.normal"]),
            _optional(arrays, f"{at}.corners"),
            [_get_cut(arrays, f"{at}.pieces.{j}", "planar") for j in range(m["pieces"])],
        )
        crack._front = _optional(arrays, f"{at}.front")
        crack._growth = _optional(arrays, f"{at}.growth")
        tear.cracks.append(crack)


# -- the whole ------------------------------------------------------------------------------
def capture_cuts(sim, arrays: dict) -> dict | None:
    """The cut and tearing state of ``sim`` (arrays into ``arrays``; its descriptor, None when
    nothing cuts or tears)."""
    cut = {n: b for n, b in sim.bodies.items() if getattr(b, "cut_state", None) is not None}
    if not (cut or sim.organ_cuts or sim.organ_tears):
        return None
    return {
        "bodies": {n: _put_body(arrays, f"cut.{n}", b) for n, b in cut.items()},
        "blades": {c.name: _put_blade(arrays, f"blade.{c.name}", c) for c in sim.organ_cuts},
        "tears": {t.body: _put_tear(arrays, f"tear.{t.body}", t) for t in sim.organ_tears},
    }


def restore_cuts(sim, meta: dict | None, arrays, path, fix: str) -> None:
    """Put the cut and tearing state ``capture_cuts`` kept into ``sim`` (set up as the run
    was, not stepped yet) before its system is built: each cut body takes its cut mesh (its
    system, state and linear solver are then made anew), each blade and crack its progress."""
    cuts_here = bool(sim.organ_cuts or sim.organ_tears)
    if meta is None:
        if cuts_here:
            raise InputError(
                f"{path} holds no cut state (written before checkpoints kept cuts, format 1); {fix}"
            )
        return
    names = sorted(c.name for c in sim.organ_cuts)
    if sorted(meta["blades"]) != names or sorted(meta["tears"]) != sorted(
        t.body for t in sim.organ_tears
    ):
        raise InputError(f"{path} holds other blades or tearing bodies than this simulation; {fix}")
    for blade in sim.organ_cuts:
        _get_blade(blade, meta["blades"][blade.name], arrays, f"blade.{blade.name}")
    for tear in sim.organ_tears:
        _get_tear(tear, meta["tears"][tear.body], arrays, f"tear.{tear.body}")
    for name, body_meta in meta["bodies"].items():
        _get_body(sim, name, body_meta, arrays, f"cut.{name}", path)
    cut = any(m["cut"] for m in meta["bodies"].values())
    if cut or any(c.suspended for c in sim.organ_cuts):  # a new topology, other pairs: anew
        sim._system, sim._state, sim._solver = None, None, None
        sim._system_dirty = True
