"""FEBio's ``<Contact>`` as scene tables: every sliding, tied and sticky pair as a
``[[penalty_contact]]`` (contact/penalty/), FEBio's own enforcement, its friction too; rigid
walls are written as ``[[rigid_wall]]`` by ``febio/constraint_sections.py``."""

from __future__ import annotations

from tissuesim.febio.model import FebModel

__all__ = ["contact_tables"]


def contact_tables(model: FebModel, names: list[str], meshes: dict) -> dict:
    """The ``[[penalty_contact]]`` tables of ``model.contacts``; ``names``: the bodies'
    names in the order of ``meshes`` (their facet sets name the surfaces)."""
    if not model.contacts:
        return {}
    owner = {}
    for name, mesh in zip(names, meshes.values(), strict=True):
        for s in mesh.facet_sets:
            owner.setdefault(s, name)
    tables = [_penalty_table(c, k, owner) for k, c in enumerate(model.contacts, start=1)]
    return {"penalty_contact": tables}


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
