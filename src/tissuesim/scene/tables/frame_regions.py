"""The tables of a frame body that say where it is: its [region] (a box, an ellipsoid, a
closed surface or a tetrahedral mesh, filled with integration points), where its frames go
([frames] grid / count / positions), and the selectors that pick frames and display-surface
points for supports, springs and point forces (``scene/tables/frames.py`` reads the rest)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.common import (
    _context,
    _is_number,
    _point_list,
    _required,
    _unknown,
    _vector3,
)
from tissuesim.validate import short

_AXES = "xyz"

PLACEMENTS = ("grid", "count", "positions")

REGION_KEYS = ("box", "ellipsoid", "surface", "mesh", "spacing", "subsamples", "display")

REGIONS = {
    "box": "box = { lower = [x, y, z], upper = [x, y, z] }",
    "ellipsoid": "ellipsoid = { center = [x, y, z], semi_axes = [a, b, c] }",
    "surface": "surface = 'organ.stl' (a closed triangle surface)",
    "mesh": "mesh = 'organ.msh' (a tetrahedral mesh)",
}

FRAME_SELECTORS = ("on_plane", "in_box", "indices", "where")

POINT_SELECTORS = ("surface_on_plane", "surface_in_box")

SELECTOR_ARGS = {
    "on_plane": ("axis", "value", "tolerance"),
    "in_box": ("lower", "upper", "tolerance"),
}


def _region(table: dict, base_dir: Path, where: str):
    """(integration points, display surface or None) from [region]."""
    from tissuesim.frames import sampling
    from tissuesim.mesh import read_mesh

    _unknown(table, REGION_KEYS, where)
    kinds = [k for k in REGIONS if k in table]
    if len(kinds) != 1:
        choices = "; ".join(REGIONS.values())
        got = f"got {kinds}" if kinds else "got none"
        raise SceneError(f"{where}: give exactly one of {choices} ({got})")
    (kind,) = kinds
    spacing = table.get("spacing")
    if spacing is None and kind != "mesh":
        raise SceneError(
            f"{where}: missing key 'spacing' (distance between integration points, e.g. 0.1)"
        )
    display = table.get("display", True)
    if not isinstance(display, bool):
        raise SceneError(f"{where}: display must be true or false, not {short(display)}")
    extra = {}
    if "subsamples" in table:
        if kind not in ("ellipsoid", "surface"):
            raise SceneError(f"{where}: subsamples applies to ellipsoid and surface, not {kind}")
        extra["subsamples"] = table["subsamples"]
    spec = table[kind]
    here = f"{where} {kind}"
    if kind in ("box", "ellipsoid"):
        keys = ("lower", "upper") if kind == "box" else ("center", "semi_axes")
        if not isinstance(spec, dict):
            raise SceneError(f"{where}: write {REGIONS[kind]}")
        _unknown(spec, keys, here)
        a, b = (_vector3(_required(spec, key, here), f"{here} {key}") for key in keys)
        with _context(here):
            if kind == "box":
                samples = sampling.sample_box(a, b, spacing)
                divisions = tuple(int(n) for n in np.maximum(1, np.round((b - a) / spacing)))
                surface = sampling.box_surface(a, b, divisions) if display else None
            else:
                samples = sampling.sample_ellipsoid(a, b, spacing, **extra)
                surface = sampling.ellipsoid_surface(a, b) if display else None
        return samples, surface
    if not isinstance(spec, str):
        raise SceneError(f"{where}: write {REGIONS[kind]}, a path relative to the scene file")
    path = Path(spec) if Path(spec).is_absolute() else base_dir / spec
    with _context(here):
        if kind == "surface":
            closed = sampling.read_surface(path)
            samples = sampling.sample_surface(closed, spacing, **extra)
            return samples, closed if display else None
        mesh = read_mesh(path)
        samples = sampling.sample_mesh(mesh, spacing)
        return samples, sampling.surface_from_mesh(mesh) if display else None


def _frame_positions(table: dict, samples, where: str) -> np.ndarray:
    """Rest frame origins (n, 3) from exactly one of grid, count, positions."""
    from tissuesim.frames.placement import farthest_point_frames, grid_frames

    given = [k for k in PLACEMENTS if k in table]
    if len(given) != 1:
        raise SceneError(
            f"{where}: give exactly one of grid = {{ lower, upper, counts }}, count = N "
            f"(farthest-point sampling of the integration points) or positions = "
            f"[[x, y, z], ...] (got {given or 'none'})"
        )
    (how,) = given
    value = table[how]
    if how == "grid":
        here = f"{where} grid"
        if not isinstance(value, dict):
            raise SceneError(
                f"{where}: write grid = {{ lower = [...], upper = [...], counts = [...] }}"
            )
        _unknown(value, ("lower", "upper", "counts"), here)
        lower = _vector3(_required(value, "lower", here), f"{here} lower")
        upper = _vector3(_required(value, "upper", here), f"{here} upper")
        counts = _required(value, "counts", here)
        ok = isinstance(counts, list) and len(counts) == 3
        if not (ok and all(isinstance(c, int) and not isinstance(c, bool) for c in counts)):
            raise SceneError(f"{here}: counts must be 3 integers >= 1, got {short(counts)}")
        with _context(here):
            return grid_frames(lower, upper, counts)
    if how == "count":
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
            raise SceneError(f"{where}: count must be an integer >= 1, got {short(value)}")
        if value > samples.n:
            raise SceneError(
                f"{where}: count = {value} frames but the region has only {samples.n} "
                f"integration points; use fewer frames or a smaller [region] spacing"
            )
        return farthest_point_frames(samples.points, value)
    return _point_list(value, f"{where} positions")


def _scale(*arrays) -> float:
    """Bounding-box diagonal of the body (integration points, frames, display surface)."""
    pts = np.concatenate([getattr(a, "points", a) for a in arrays if a is not None])
    return float(np.linalg.norm(np.ptp(pts, axis=0)))


def _bbox(points: np.ndarray) -> str:
    lo, hi = points.min(axis=0), points.max(axis=0)
    return " x ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi, strict=True))


def _match(points: np.ndarray, how: str, args, scale: float, where: str) -> tuple[np.ndarray, str]:
    """Mask of ``points`` on a plane / in a box (tissuesim.mesh.select's rules) and its text."""
    if not isinstance(args, dict):
        raise SceneError(
            f"{where}: {how} takes a table of arguments "
            f"{{ {', '.join(f'{a} = ...' for a in SELECTOR_ARGS[how][:2])} }}"
        )
    _unknown(args, SELECTOR_ARGS[how], where)
    tol = args.get("tolerance")
    if tol is None:
        tol = 1e-6 * scale
    elif not (_is_number(tol) and tol >= 0):
        raise SceneError(f"{where}: tolerance must be a number >= 0, not {short(tol)}")
    if how == "on_plane":
        axis = _required(args, "axis", where)
        if not (isinstance(axis, int) and not isinstance(axis, bool) and 0 <= axis <= 2):
            raise SceneError(f"{where}: axis must be 0, 1 or 2 (x, y or z), not {short(axis)}")
        value = _required(args, "value", where)
        if not _is_number(value):
            raise SceneError(f"{where}: value must be a number, not {short(value)}")
        mask = np.abs(points[:, axis] - value) <= tol
        return mask, f"on the plane {_AXES[axis]} = {value} (tolerance {tol:.3g})"
    lo = _vector3(_required(args, "lower", where), f"{where} lower")
    hi = _vector3(_required(args, "upper", where), f"{where} upper")
    mask = ((points >= lo - tol) & (points <= hi + tol)).all(axis=1)
    return mask, f"in the box {lo.tolist()} to {hi.tolist()} (tolerance {tol:.3g})"


def _one_selector(selector, kinds: tuple[str, ...], key: str, example: str, where: str):
    if not isinstance(selector, dict) or len(selector) != 1:
        raise SceneError(
            f"{where}: {key} must be a table with one selector out of {list(kinds)}, "
            f"e.g. {key} = {example}"
        )
    ((how, args),) = selector.items()
    _unknown([how], kinds, f"{where} {key}")
    return how, args


def _select_frames(body, selector, scale: float, where: str) -> np.ndarray:
    """Sorted frame indices picked by on_plane / in_box / where (rest origins) or indices."""
    how, args = _one_selector(
        selector, FRAME_SELECTORS, "frames", "{ on_plane = { axis = 2, value = 0.0 } }", where
    )
    X = body.rest_frames
    here = f"{where} frames {how}"
    if how == "where":  # a condition on the frames' rest origins, as for mesh vertices
        from tissuesim.scene.common import condition

        ids = np.flatnonzero(condition(args, here)(X))
        if not ids.size:
            raise SceneError(
                f"{here}: {args!r} selects no frame; the {len(X)} frames' rest origins span "
                f"{_bbox(X)}"
            )
        return ids
    if how == "indices":
        n = len(X)
        ok = isinstance(args, list) and args
        if not (ok and all(isinstance(i, int) and not isinstance(i, bool) for i in args)):
            raise SceneError(
                f"{here}: expected a list of frame indices, e.g. [0, 1], got {short(args)}"
            )
        bad = [i for i in args if not 0 <= i < n]
        if bad:
            raise SceneError(f"{here}: frame indices must be in 0..{n - 1}, got {bad}")
        return np.unique(np.asarray(args, dtype=np.int64))
    mask, text = _match(X, how, args, scale, here)
    if not mask.any():
        raise SceneError(
            f"{here}: no frames {text}; the {len(X)} frames' rest origins span {_bbox(X)}"
        )
    return np.flatnonzero(mask)


def _points(body, spec, scale: float, where: str) -> np.ndarray:
    """(k, 3) rest points: an explicit list, or display-surface vertices picked by a selector."""
    if isinstance(spec, list):
        return _point_list(spec, f"{where} points")
    how, args = _one_selector(
        spec,
        POINT_SELECTORS,
        "points",
        "[[x, y, z], ...] or { surface_on_plane = { axis = 2, value = 2.0 } }",
        where,
    )
    here = f"{where} points {how}"
    if body.surface is None:
        raise SceneError(
            f"{here}: selects display-surface vertices but the body has no display surface; "
            f"set display = true in [region], or list the points as [[x, y, z], ...]"
        )
    P = body.surface.points
    mask, text = _match(P, how.removeprefix("surface_"), args, scale, here)
    if not mask.any():
        raise SceneError(
            f"{here}: no display-surface vertices {text}; the surface spans {_bbox(P)}"
        )
    return P[mask]
