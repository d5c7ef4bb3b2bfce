"""FEBio's ``<Contact>`` as scene tables: rigid walls as plane obstacles, frictional sliding pairs
as the barrier's pairs, frictionless sliding, tied and sticky pairs as ``[[penalty_contact]]``
(contact/penalty/)."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.curves import load_expression as _times
from tissuesim.febio.model import FebModel, Load

__all__ = ["contact_tables"]


def contact_tables(model: FebModel, names: list[str], bodies: list[dict], meshes: dict) -> dict:
    if not model.contacts:
        return {}
    owner = {}
    for name, mesh in zip(names, meshes.values(), strict=True):
        for s in mesh.facet_sets:
            owner.setdefault(s, name)
    surfaces: dict[str, list[str]] = {}
    pairs, obstacles, penalty = [], [], []
    scale = float(np.linalg.norm(np.ptp(model.nodes, axis=0)))
    for k, c in enumerate(model.contacts, start=1):
        if "penalty" in c:  # FEBio's penalty / augmented Lagrangian, as FEBio enforces it
            penalty.append(_penalty_table(c, k, owner))
            continue
        sides = []
        for s in c["surfaces"]:
            if s not in owner:
                raise c["node"].error(f"surface {s!r} is on no body")
            surfaces.setdefault(owner[s], [])
            if s not in surfaces[owner[s]]:
                surfaces[owner[s]].append(s)
            sides.append(owner[s])
        if c["type"] == "rigid_wall":
            a, b, cc, d = c["plane"]
            n = np.array([a, b, cc])
            point = d * n / (n @ n)
            unit = n / np.linalg.norm(n)
            wall = f"wall{k}"
            offset = c["offset"]
            move = [_times(Load(offset.value[0] * unit, offset.curve, offset.window), model, i)
                    for i in range(3)]  # fmt: skip
            obstacles.append(
                {
                    "name": wall,
                    "plane": {"point": point.tolist(), "normal": n.tolist(), "size": 4 * scale},
                    "translation": move,
                }
            )
            sides.append(wall)
        elif sides[0] == sides[1]:
            raise c["node"].error("contact of a body with itself is not supported by tissuesim")
        pairs.append({"bodies": sides, "friction": c["friction"]})
    multi = {n for n, s in surfaces.items() if len(s) > 1}
    if multi:
        body = sorted(multi)[0]
        raise model.contacts[0]["node"].error(
            f"body {body!r} touches through several surfaces {surfaces[body]}: tissuesim takes "
            "one contact surface per body (join them into one Surface)"
        )
    if not pairs and not obstacles:
        return {"penalty_contact": penalty}
    listed = {tuple(sorted(p["bodies"])) for p in pairs}
    everyone = names + [o["name"] for o in obstacles]
    for i, a in enumerate(everyone):
        for b in everyone[i:]:
            if (a, b) != tuple(sorted((a, b))) or tuple(sorted((a, b))) in listed:
                continue
            if a in names or b in names:
                pairs.append({"bodies": [a, b], "enabled": False})
    out = {"contact": {"surfaces": {n: s[0] for n, s in surfaces.items()}, "pairs": pairs}}
    if obstacles:
        out["obstacles"] = obstacles
    if penalty:
        out["penalty_contact"] = penalty
    return out


def _penalty_table(c: dict, k: int, owner: dict) -> dict:
    """A FEBio sliding contact as a [[penalty_contact]] table (FEBio's primary surface is the
    one whose points are projected: ``FEFacet2FacetSliding::m_ss``)."""
    primary, secondary = c["surfaces"]
    for s in (primary, secondary):
        if s not in owner:
            raise c["node"].error(f"surface {s!r} is on no body")
    if primary == secondary:
        raise c["node"].error(
            f"contact of surface {primary!r} with itself is not supported by tissuesim"
        )
    name = c["node"].attrib.get("name") or f"contact{k}"
    return {"name": name, "primary": owner[primary], "secondary": owner[secondary],
            "primary_facets": primary, "secondary_facets": secondary, **c["penalty"]}  # fmt: skip
