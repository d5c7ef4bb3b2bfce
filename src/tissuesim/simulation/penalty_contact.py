"""``Simulation.add_penalty_contact`` (a mixin): FEBio-style penalty / augmented-Lagrangian
contact between two FEM bodies' facet surfaces (``contact/penalty/pair.py``), built into the
system with the other energies. The barrier contact (``set_contact``) keeps surfaces apart
with a guarantee; this one lets them overlap by what the penalty allows, as FEBio's sliding
contacts do: it is what a FEBio model's contact converts to."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["PenaltyContactCalls", "PenaltySpec", "INTEGRATIONS", "AREAS", "carry_penalty_state"]

#: where the contact's points are: Gauss points of the primary facets (FEBio's
#: sliding-facet-on-facet and sliding-elastic) or their corners (sliding-node-on-facet)
INTEGRATIONS = ("gauss", "nodes")
#: the area the points' weights measure: the rest surface, or the current one (lagged)
AREAS = ("reference", "current")


@dataclass(frozen=True)
class PenaltySpec:
    name: str
    primary: str
    secondary: str
    primary_facets: object
    secondary_facets: object
    penalty: float
    auto_penalty: bool
    integration: str
    area: str
    two_pass: bool
    augmented: bool
    tolerance: float
    gap_tolerance: float
    min_augmentations: int
    max_augmentations: int
    search_tolerance: float
    tied: bool = False
    sticky: bool = False
    snap_tolerance: float = 0.0
    max_traction: float = 0.0
    friction: float = 0.0
    friction_penalty: float = 0.0
    friction_anchor: str = "step"
    keep_last_augmentation: bool = False
    special_cases: bool = False
    tension: bool = False


class PenaltyContactCalls:
    """Mixed into ``Simulation`` (which sets ``self.penalty_contacts = []``)."""

    def add_penalty_contact(
        self,
        primary: str,
        secondary: str,
        *,
        primary_facets=None,
        secondary_facets=None,
        penalty: float | None = None,
        auto_penalty: bool = False,
        integration: str = "gauss",
        area: str = "reference",
        two_pass: bool = False,
        augmented: bool = False,
        tolerance: float = 0.0,
        gap_tolerance: float = 0.0,
        min_augmentations: int = 0,
        max_augmentations: int = 10,
        search_tolerance: float = 0.01,
        tied: bool = False,
        sticky: bool = False,
        snap_tolerance: float = 0.0,
        max_traction: float = 0.0,
        friction: float = 0.0,
        friction_penalty: float = 0.0,
        friction_anchor: str = "step",
        keep_last_augmentation: bool = False,
        special_cases: bool = False,
        tension: bool = False,
        name: str | None = None,
    ) -> str:
        """Penalty contact: points of body ``primary``'s facets (a facet set name, (k, 3) or
        (k, 4) vertex indices, or None: its whole boundary) pressed out of body
        ``secondary``'s facets with the pressure ``penalty`` x penetration (``penalty`` in
        Pa/m; with ``auto_penalty`` a factor on FEBio's automatic penalty, the Young's modulus x
        facet area / element volume, per primary facet; default 1 then). ``integration``
        "gauss" or "nodes" (FEBio's node-on-facet); ``area`` "reference" or "current";
        ``two_pass``: the secondary's points pressed out of the primary too; ``augmented``:
        FEBio's augmented Lagrangian, augmenting until the multipliers' norm changes by less
        than ``tolerance`` (relative) and the rms penetration is under ``gap_tolerance`` (m),
        ``min_augmentations`` to ``max_augmentations`` times per step. A point is in contact
        where its projection falls on a facet within ``search_tolerance`` (natural
        coordinates). ``tied``: each point is held where it projects at rest (FEBio's
        tied contacts; the vector gap, tension too); ``sticky``: a point is tied where it
        projects once it comes within ``snap_tolerance`` (m) of the secondary surface, and lets
        go where its normal traction passes ``max_traction`` (Pa; 0: never; FEBio's sticky
        contact). ``friction``: Coulomb's coefficient, stick held by the tangential penalty
        ``friction_penalty`` (Pa/m; 0: the normal penalty) and slip at friction x pressure,
        FEBio's return map (contact/penalty/friction.py), from anchors set where the points
        project at each step's start (``friction_anchor`` "step", FEBio's sliding-elastic) or
        where they first projected ("contact", its node-on-facet). ``keep_last_augmentation``:
        the augmentation that finds the multipliers converged is kept for the next step
        (FEBio's sliding-elastic). ``special_cases``: a point whose projection lands on no
        facet is projected onto an interior edge of the secondary surface or its closest node
        (FEBio's node-on-facet, facet-on-facet, tied and sticky contacts; the gap is the
        signed distance there; linear facets only: contact/penalty/special_cases.py).
        ``tension``: a point whose projection lies on a facet stays in contact as the surfaces
        pull apart, its traction tensile (FEBio's sliding-elastic ``tension = 1``). Its
        force on ``primary`` is reported by ``forces()`` under ``name`` (default
        ``penalty_contact<n>``). Returns the name."""
        for body in (primary, secondary):
            if body not in self.bodies or self.bodies[body].kind != "fem":
                raise InputError(
                    f"add_penalty_contact: {short(body)} is not a FEM body; FEM bodies: "
                    f"{sorted(n for n, b in self.bodies.items() if b.kind == 'fem') or 'none'}"
                )
        if integration not in INTEGRATIONS:
            raise InputError(
                f"add_penalty_contact: integration {short(integration)}: give one of "
                f"{', '.join(INTEGRATIONS)}"
            )
        if area not in AREAS:
            raise InputError(
                f"add_penalty_contact: area {short(area)}: give one of {', '.join(AREAS)}"
            )
        if penalty is None:
            if not auto_penalty:
                raise InputError(
                    "add_penalty_contact: give penalty (Pa/m), or auto_penalty = True (FEBio's "
                    "automatic penalty: Young's modulus x facet area / element volume)"
                )
            penalty = 1.0
        if tied and sticky:
            raise InputError("add_penalty_contact: a pair is tied or sticky, not both")
        from tissuesim.contact.penalty.friction import ANCHORS

        if friction_anchor not in ANCHORS:
            raise InputError(
                f"add_penalty_contact: friction_anchor {short(friction_anchor)}: give one of "
                f"{', '.join(ANCHORS)}"
            )
        if tension and (tied or sticky or friction):
            raise InputError(
                "add_penalty_contact: tension = True on a tied or sticky pair (held in tension "
                "already) or with friction (FEBio refuses it too); give tension = False"
            )
        if friction and (tied or sticky):
            raise InputError(
                "add_penalty_contact: friction on a tied or sticky pair: its points are held "
                "already; give friction = 0"
            )
        checks = {"penalty": (penalty, True), "tolerance": (tolerance, False),
                  "snap_tolerance": (snap_tolerance, False),
                  "max_traction": (max_traction, False),
                  "gap_tolerance": (gap_tolerance, False),
                  "search_tolerance": (search_tolerance, False),
                  "friction": (friction, False),
                  "friction_penalty": (friction_penalty, False)}  # fmt: skip
        for key, (value, positive) in checks.items():
            ok = isinstance(value, int | float) and np.isfinite(value)
            ok = ok and (value > 0 if positive else value >= 0)
            if not ok:
                raise InputError(
                    f"add_penalty_contact: {key} = {short(value)}: give a "
                    f"{'positive' if positive else 'non-negative'} number"
                )
        if not (0 <= int(min_augmentations) <= int(max_augmentations)):
            raise InputError(
                f"add_penalty_contact: min_augmentations = {min_augmentations}, max_augmentations "
                f"= {max_augmentations}: give 0 <= min <= max"
            )
        name = self._claim_force_name(name, f"penalty_contact{len(self.penalty_contacts) + 1}")
        self.penalty_contacts.append(
            PenaltySpec(
                name,
                primary,
                secondary,
                primary_facets,
                secondary_facets,
                float(penalty),
                bool(auto_penalty),
                integration,
                area,
                bool(two_pass),
                bool(augmented),
                float(tolerance),
                float(gap_tolerance),
                int(min_augmentations),
                int(max_augmentations),
                float(search_tolerance),
                bool(tied),
                bool(sticky),
                float(snap_tolerance),
                float(max_traction),
                float(friction),
                float(friction_penalty),
                friction_anchor,
                bool(keep_last_augmentation),
                bool(special_cases),
                bool(tension),
            )  # fmt: skip
        )
        self._system_dirty = True
        return name

    def _penalty_pairs(self, system) -> list:
        """The system's PenaltyContact pairs (its bodies' indices), set up at rest."""
        from tissuesim.contact.penalty.pair import PenaltyContact

        pairs = []
        for spec in self.penalty_contacts:
            if spec.primary not in system.names or spec.secondary not in system.names:
                continue
            sides = []
            for body, facets in ((spec.primary, spec.primary_facets),
                                 (spec.secondary, spec.secondary_facets)):  # fmt: skip
                j = system.names.index(body)
                sides.append(_side(spec, body, j, system.bodies[j], facets))
            pair = PenaltyContact(
                spec.name, sides[0], sides[1], spec.penalty,
                rule="nodal" if spec.integration == "nodes" else "gauss", area=spec.area,
                two_pass=spec.two_pass, augmented=spec.augmented, tolerance=spec.tolerance,
                gap_tolerance=spec.gap_tolerance, min_augmentations=spec.min_augmentations,
                max_augmentations=spec.max_augmentations,
                search_tolerance=spec.search_tolerance, tied=spec.tied, sticky=spec.sticky,
                snap_tolerance=spec.snap_tolerance, max_traction=spec.max_traction,
                friction=spec.friction, friction_penalty=spec.friction_penalty,
                friction_anchor=spec.friction_anchor,
                keep_last_augmentation=spec.keep_last_augmentation,
                special_cases=spec.special_cases, tension=spec.tension,
            )  # fmt: skip
            pair.setup([None if b is None else b for b in _rest(system)])
            pairs.append(pair)
        return pairs

    def _penalty_forces(self, system, c: np.ndarray) -> dict:
        positions, _ = system.body_positions_and_dofs(c)
        return {p.name: p.forces(positions)[0].tolist() for p in system.penalty_contacts}


def carry_penalty_state(old: list, new: list) -> None:
    """Keep each pair's multipliers and lagged weights across a system rebuild where its
    points are the same."""
    by_name = {p.name: p for p in old}
    for pair in new:
        before = by_name.get(pair.name)
        if before is None or len(before.passes) != len(pair.passes):
            continue
        for a, b in zip(before.passes, pair.passes, strict=True):
            if a.multipliers.shape == b.multipliers.shape:
                b.multipliers, b.weights = a.multipliers, a.weights
                b.friction = a.friction if b.friction is not None else None


def _rest(system) -> list:
    return [None if not hasattr(b, "mesh") else b.mesh.points for b in system.bodies]


def _side(spec: PenaltySpec, body: str, j: int, model, facets):
    """One surface of a pair: its facets (vertex indices of body j) and the per-facet scale
    (FEBio's auto penalty: E A / V of the element behind the facet; 1 without)."""
    from tissuesim.contact.pairs import contact_facets
    from tissuesim.contact.penalty.faces import Facets, with_midsides
    from tissuesim.contact.penalty.pair import PenaltySide

    mesh = model.mesh
    if mesh.dim != 3:
        raise InputError(f"penalty contact {spec.name!r}: body {body!r} is not 3D")
    if isinstance(facets, str) and facets in mesh.facet_sets:
        rows = np.asarray(mesh.facet_sets[facets])
    elif facets is None or isinstance(facets, str):
        rows = contact_facets(body, mesh, facets)  # the boundary, or its one-line error
    else:
        rows = np.asarray(facets)
    f = Facets.of(rows, f"penalty contact {spec.name!r}, body {body!r}")
    if f.nodes.max() >= mesh.n_points or f.nodes.min() < 0:
        raise InputError(
            f"penalty contact {spec.name!r}: body {body!r} has {mesh.n_points} vertices; a "
            "facet names one outside 0..n-1"
        )
    try:  # a quadratic body's facets are quadratic (FEBio's quad8 / tri6 surface elements)
        f = with_midsides(mesh, f)
    except InputError as exc:
        raise InputError(f"penalty contact {spec.name!r}, body {body!r}: {exc}") from None
    scale = np.ones(len(f.nodes))
    if spec.auto_penalty:
        scale = _auto_scale(model, f)
    return PenaltySide(j, f, scale)


def _auto_scale(model, facets) -> np.ndarray:
    """FEBio's ``FEContactInterface::AutoPenalty``: E x (facet area) / (volume of the element
    the facet bounds), at rest; E the material's Young's modulus (isotropic small-strain
    equivalent, ``mu (3 lam + 2 mu) / (lam + mu)``; in a body of regions, the region's of the
    element behind the facet)."""
    from tissuesim.contact.penalty.faces import area_jacobians, sample_points

    mesh = model.mesh
    cells = np.asarray(mesh.cells)
    volumes = model.kinematics.cell_weights
    material = model.material  # a body of regions: each cell's region's moduli
    mu = np.asarray(getattr(material, "cell_mu", material.mu), float)
    lam = np.asarray(getattr(material, "cell_lam", material.lam), float)
    E = mu * (3 * lam + 2 * mu) / (lam + mu)
    E = np.broadcast_to(E, (len(cells),)) if E.ndim == 0 else E
    points = sample_points(facets, "gauss")
    area = np.bincount(points.facet, points.weight * area_jacobians(mesh.points, facets, points),
                       minlength=len(facets.nodes))  # fmt: skip
    # the cell behind each facet: the one holding all its distinct corners, found as the
    # largest entry of (facet x vertex) @ (vertex x cell) incidence counts
    import scipy.sparse as sp

    n = mesh.n_points
    A = sp.csr_matrix((np.ones(cells.size), (cells.ravel(), np.repeat(np.arange(len(cells)),
                       cells.shape[1]))), shape=(n, len(cells)))  # fmt: skip
    A.data[:] = 1.0  # a vertex counted once per cell
    nodes = facets.nodes
    distinct = facets.kind  # a row's nodes past its kind repeat its last
    rows = np.repeat(np.arange(len(nodes)), nodes.shape[1])
    F = sp.csr_matrix((np.ones(nodes.size), (rows, nodes.ravel())), shape=(len(nodes), n))
    F.data[:] = 1.0  # a repeated node once
    shared = (F @ A).tocsr()
    cell = np.asarray(shared.argmax(axis=1)).ravel()
    held = np.asarray(shared[np.arange(len(nodes)), cell]).ravel()
    missing = np.flatnonzero(held < distinct)
    if len(missing):
        raise InputError(
            f"penalty contact auto_penalty: facet {nodes[missing[0]].tolist()} bounds no "
            "element of its body; give penalty without auto_penalty"
        )
    return E[cell] * area / volumes[cell]
