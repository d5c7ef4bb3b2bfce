"""Cuts and tearing in a ``Simulation`` (a mixin): blades through the connective tissue or a
FEM body (``add_cut``), tearing (``set_tearing``), a FEM body cut now by the virtual node
algorithm (``cut_body``), and what a step does with them: the cut made ahead of a blade in
contact before the step, the kerf ahead of it opened, the cuts and cracks made after it."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import short

if TYPE_CHECKING:
    from tissuesim.coupling.tissue import TissueBody

__all__ = ["CutCalls"]


class CutCalls:
    """Mixed into ``Simulation``."""

    # -- blades and tearing -------------------------------------------------------------------
    def _tissue(self, what: str) -> TissueBody:
        if self.tissue is None:
            raise InputError(f"{what} acts on the tissue: call add_tissue first")
        return self.tissue

    def add_cut(
        self,
        blade,
        start: float,
        end: float,
        *,
        body: str | None = None,
        kerf=None,
        name: str = "cut",
        toughness: float = 0.0,
        edge: Sequence[int] | None = None,
        contact: bool | None = None,
    ):
        """A blade sweeping from ``start`` to ``end`` (s). Without ``body`` it dissects the
        connective tissue (``add_tissue`` first): ``blade(t)`` returns a polyline (k, 3) of
        k >= 2 points (m); the tissue points within ``kerf`` (m; default half the tissue's
        sample spacing) of the swept surface are removed and frames stop acting across the
        cut; the swept surface is written as the series ``name``. With ``body`` (a FEM body)
        it cuts that body: ``blade(t)`` returns its straight edge (2, 3) or a flat triangular
        blade's corners (3, 3), moving in its own plane or off it (then along the surface it
        sweeps, ``mesh/cutting/swept_cut.py``); after each step the cells it has swept through
        completely are cut by the virtual node algorithm (``cut_body``), mass kept; its
        cutting force (``toughness``, J/m^2 of new surface) is reported as ``name``
        and the cut's area per step under ``extra["cuts"]``. Returns the cutting tool.

        ``blade`` may instead name an obstacle (an instrument): its surface's vertices
        ``edge`` (2 or 3 indices; default its only triangle) are the blade, moved with it,
        also when it is driven live (``drive_obstacle``); ``end`` may then be ``math.inf``.
        With contact on (``set_contact``) the instrument is in contact with the body it cuts
        as with every other (``contact``, default True): before each step the cells it will
        touch in the step are cut (``mesh/cutting/cut_ahead.py``), so it moves in the cut's kerf and
        the cut's faces never pass through it; ``contact=False`` lets it pass through the body
        it cuts, which is then cut after each step. ``name``'s force is what the instrument
        feels: the cutting resistance plus the contact force of the bodies on it.

        ``sim.add_cut(lambda t: np.array([[t - 1, -0.2, 0.15], [t - 1, 1.2, 0.15]]),
        start=1.0, end=2.0)`` sweeps a straight blade along x."""
        if body is not None:
            from tissuesim.bodies.organ_cut import OrganCut

            b = self.body(body, ("fem",))
            self._no_cut_with_visual(b.name, f"add_cut {name!r}")
            self._no_cut_of_rigid(b.name, f"add_cut {name!r}")
            if kerf is not None:
                raise InputError(
                    f"add_cut: kerf is for cuts of the connective tissue; a cut of body "
                    f"{b.name!r} follows the blade's plane and removes nothing: leave kerf out"
                )
            if any(c.name == name for c in self.organ_cuts) or name in self.bodies:
                raise InputError(f"add_cut: the name {name!r} is taken; give the cut its own")
            obstacle = None
            if isinstance(blade, str):
                obstacle, blade = blade, self._obstacle_blade(blade, edge, name)
            elif edge is not None:
                raise InputError("add_cut: edge picks an obstacle's vertices; blade is no obstacle")
            if contact is None:
                contact = obstacle is not None
            elif not isinstance(contact, bool):
                raise InputError(f"add_cut: contact must be true or false, not {contact!r}")
            tool = OrganCut(
                blade, float(start), float(end), b.name, name, float(toughness), obstacle, contact
            )
            self.organ_cuts.append(tool)
            if obstacle is not None:
                self._changed()  # the blade leaves the body it cuts out of its contact
            return tool
        if isinstance(blade, str) or edge is not None:
            raise InputError("add_cut: an obstacle as the blade cuts a FEM body: give body = '...'")
        return self._tissue("add_cut").add_cut(blade, start, end, kerf=kerf, name=name)

    def _obstacle_blade(self, obstacle: str, edge, cut: str):
        """blade(t): the vertices ``edge`` of obstacle ``obstacle`` where it is at t (looked
        up at each call: driving replaces the obstacle's motion)."""
        names = [ob.name for ob in self.obstacles]
        if obstacle not in names:
            known = ", ".join(names) or "none"
            raise InputError(f"add_cut {cut!r}: no obstacle {obstacle!r} (obstacles: {known})")
        surface = self.obstacles[names.index(obstacle)].surface
        if edge is None:
            if len(surface.triangles) != 1:
                raise InputError(
                    f"add_cut {cut!r}: obstacle {obstacle!r} has {len(surface.triangles)} "
                    "triangles: give edge = (i, j) or (i, j, k), the vertices of its blade"
                )
            edge = surface.triangles[0]
        from tissuesim.validate import indices

        ids = indices(edge, f"add_cut {cut!r}: edge", len(surface.points))
        if ids.size not in (2, 3) or len(set(ids.tolist())) != ids.size:
            raise InputError(
                f"add_cut {cut!r}: edge must be 2 or 3 distinct vertices of obstacle "
                f"{obstacle!r} (an edge or a triangle), not {short(edge)}"
            )

        def blade(t: float) -> np.ndarray:
            ob = next(o for o in self.obstacles if o.name == obstacle)
            return ob.positions(t)[ids]

        return blade

    def set_tearing(
        self,
        threshold: float | None = None,
        *,
        body: str | None = None,
        stress: float | None = None,
        stretch: float | None = None,
    ) -> None:
        """Let tissue tear. Without ``body``: the connective tissue (``add_tissue`` first);
        after each step, tissue points whose largest principal Green strain exceeds
        ``threshold`` (dimensionless, e.g. 0.5) are removed. With ``body`` (a FEM body): it
        tears where its largest principal Cauchy stress exceeds ``stress`` (Pa, its strength)
        or its largest principal stretch exceeds ``stretch``: a crack normal to that stress
        grows through the elements over the threshold, cut like a blade's cut
        (``bodies/organ_tear.py``); once its cracks stop, a new one may start far from them.
        Reported as the cuts ``body.tear`` (``body.tear2``, ... for later cracks) in
        ``extra["cuts"]``."""
        if body is None:
            if threshold is None or stress is not None or stretch is not None:
                raise InputError(
                    "set_tearing: the connective tissue tears at a strain threshold "
                    "(set_tearing(0.5)); stress= and stretch= are for a body (body='...')"
                )
            self._tissue("set_tearing").set_tearing(threshold)
            return
        from tissuesim.bodies.organ_tear import BodyTearing

        b = self.body(body, ("fem",))
        self._no_cut_with_visual(b.name, "set_tearing")
        self._no_cut_of_rigid(b.name, "set_tearing")
        if threshold is not None:
            raise InputError(
                f"set_tearing: body {b.name!r} tears at a stress (stress=, Pa) or a stretch "
                "(stretch=), not at a strain threshold"
            )
        self.organ_tears = [t for t in self.organ_tears if t.body != b.name]
        self.organ_tears.append(BodyTearing(b.name, stress, stretch))

    # -- cutting a FEM body, and what a step does with cuts -----------------------------------
    def cut_body(self, cut, *, body: str | None = None, name: str = "cut") -> dict:
        """Cut a FEM body now along ``cut`` (a ``mesh.virtual_nodes.PlanarCut`` in world
        coordinates: the blade cuts the body where it is) by the virtual node algorithm: the
        cells it crosses completely become copies per side with their volume fractions, nodes
        are duplicated where the material separates, positions and velocities carry over, and
        supports and graspers hold every copy of their vertices. A body can be cut again: a
        cut of the same ``name`` in the same plane with a larger polygon goes on (a blade
        advancing step by step: each cell is cut once, where the body was when the blade
        crossed it), another name is another cut. Returns what changed: {"cells_cut" (new),
        "new_nodes", "pieces", "area_m2" (the rest area of this cut so far), "origin": (n,)
        the node each node continues}. With contact on, the cut body's contact surface is its
        cut boundary (``contact/cut/surface.py``, in 2D ``contact/cut/surface_2d.py``: each
        side's cut face a little inside it, so the two never pass through each other). A
        tissue's attachment points on the body follow the copy on their side of the cut. A
        cell several cuts cross is split into the parts between them."""
        from tissuesim.bodies.cut_state import CutState, recut

        b = self.body(body, ("fem",))
        self._no_cut_with_visual(b.name, "cut_body")
        self._no_cut_of_rigid(b.name, "cut_body")
        if b.mesh.order != 1 or not b.mesh.simplicial:
            raise InputError(
                f"cut_body: body {b.name!r} has {b.mesh.cell_type} cells; cuts apply to P1 "
                "triangles and tetrahedra"
            )
        if b.pressures:
            raise InputError(
                f"cut_body: body {b.name!r} carries a follower pressure; a cut would change "
                "the surface it acts on: cut a body without one"
            )
        if b.cut_state is None:
            b.cut_state = CutState.of_model(b.model)
        current = self.body_positions(b.name) if self._state is not None else b.mesh.points
        old_vn = b.cut_state.vn
        before_cells = b.cut_state.vn.n_cell_cuts if b.cut_state.vn else 0
        before = b.mesh.n_points
        done = recut(b.cut_state, cut, name, current)
        if done is None:  # no new cell crossed completely: nothing changes
            vn, names = b.cut_state.vn, b.cut_state.names
            area = 0.0
            if vn is not None and name in names:
                area = float(b.cut_state.areas(vn)[names.index(name)])
            return {
                "cells_cut": 0,
                "new_nodes": 0,
                "pieces": 1 if vn is None else vn.n_pieces,
                "area_m2": area,
                "origin": np.arange(before),
            }
        vn, carry, index = done
        if self.contact is not None:  # pieces too small to move on their own stay attached
            from tissuesim.bodies.cut_state import attach_crumbs_in_contact

            dhat, blade = self._contact_dhat(), self._blade_in(b.name)
            vn, carry = attach_crumbs_in_contact(b.cut_state, vn, carry, dhat, blade)
        b.apply_cut(vn, carry, b.cut_state)
        if self.tissue is not None:  # its attachment points follow their side of the cut
            from tissuesim.bodies.cut_state import follow_cells

            self.tissue.follow_organ_cut(
                b.name, lambda cells, bary: follow_cells(old_vn, vn, cells, bary)
            )
        return {
            "cells_cut": vn.n_cell_cuts - before_cells,
            "new_nodes": len(vn.points) - before,
            "pieces": vn.n_pieces,
            "area_m2": float(b.cut_state.areas(vn)[index]),
            "origin": carry,
        }

    def _blade_in(self, body: str) -> bool:
        """Whether an instrument in contact cuts FEM body ``body`` (its cut faces then sit
        further in: ``contact/cut/surface.py`` BLADE_GAP)."""
        return any(c.body == body and self._cuts_ahead(c) for c in self.organ_cuts)

    def _cuts_ahead(self, blade) -> bool:
        """Whether ``blade`` is in contact with the body it cuts (an obstacle's, contact on):
        its cut is made before each step (``_cut_ahead``)."""
        return blade.contact and self.contact is not None

    def _cut_ahead(self) -> None:
        """Before a step: each blade in contact with the body it cuts cuts every cell it will
        touch in the step, where the body is now (``mesh/cutting/cut_ahead.py``), so that it moves
        in the cut's kerf; what that changed is reported after the step."""
        from tissuesim.bodies.organ_cut import STEP_SAMPLES
        from tissuesim.mesh.cutting.cut_ahead import MARGIN, cut_ahead

        t0, t1 = self.time, self.time + self.time_step
        for blade in self.organ_cuts:
            lo, hi = max(t0, blade.start), min(t1, blade.end)
            blade.path = None
            if not self._cuts_ahead(blade):
                continue
            swept = None
            if hi > lo:
                blade.record(t0, t1)
                swept = blade.swept(t1)
            if swept is None:
                if blade.suspended:
                    self._check_blade_start(blade)
                continue
            b = self.body(blade.body, ("fem",))
            current = self.body_positions(b.name) if self._state is not None else b.mesh.points
            state = b.cut_state
            x_cell = current[b.mesh.cells] if state is None else state.cell_positions(current)
            blades = [blade.edge(t) for t in np.linspace(lo, hi, STEP_SAMPLES)]
            blade.path = blades
            following = None  # where a prescribed blade will be a step later (its lead)
            if self._prescribed_motion(blade.obstacle):
                following = blade.edge(min(t1 + self.time_step, blade.end))
            cut = cut_ahead(swept, x_cell, blades, MARGIN * self._contact_dhat(), following)
            done = self.cut_body(cut, body=b.name, name=blade.name)
            if blade.pending is not None:  # a step that failed and is taken again
                done["cells_cut"] += blade.pending["cells_cut"]
            blade.pending = done
            self._check_blade_start(blade)

    def _clear_blade_paths(self, c: np.ndarray) -> np.ndarray | None:
        """The configuration ``c`` with the kerf ahead of each blade in contact opened where
        the body closed it on the blade's path in this step (``contact/cut/blade_clearance.py``), or
        None when no blade's path needs it: a step's start when ``c`` is not one."""
        from tissuesim.contact.cut.blade_clearance import clearance
        from tissuesim.contact.cut.surface import BLADE_GAP

        s, contact = self.system, self.system.contact
        out = None
        for blade in self.organ_cuts:
            if blade.path is None or blade.suspended or blade.curved or blade.normal is None:
                continue
            b = self.bodies[blade.body]
            vn = None if b.cut_state is None else b.cut_state.vn
            if vn is None or b.name not in s.names or b.name not in contact.slices:
                continue
            config = s.config_slices[s.index(b.name)]
            dim = b.mesh.points.shape[1]
            if dim != 3:
                continue
            rows, surface = contact.slices[b.name]
            weights = getattr(surface, "embedding", None)  # a cut body's surface: V = W X
            if weights is None:
                continue
            base = c if out is None else out
            copies = vn.side != 0
            move = clearance(
                base[config].reshape(-1, dim),
                vn.cells[copies],
                vn.level[copies],
                weights,
                contact.vertices(base)[rows],
                blade.path,
                blade.point,
                blade.normal,
                BLADE_GAP * contact.dhat,
                2.0 * BLADE_GAP * contact.dhat,
            )
            if move is not None:
                out = base.copy()
                out[config] += move.ravel()
        return out

    def _prescribed_motion(self, name: str | None) -> bool:
        """Whether obstacle ``name`` moves as prescribed (a function of t, or not at all), so
        that where it will be after the coming step is known; not when driven live."""
        from tissuesim.contact.obstacles import DrivenMotion

        ob = next((o for o in self.obstacles if o.name == name), None)
        return ob is not None and not any(
            isinstance(m, DrivenMotion) for m in (ob.translation, ob.rotation)
        )

    def _check_blade_start(self, blade) -> None:
        """The blade must start the step outside the body it cuts. Where the body has moved
        since cells next to the new ones were cut (each node keeps its distance to the cut from
        then), a new cut face can cross the blade: the blade then leaves that body's contact
        for the step (``blade_contact`` False in the cut's report) and the next step tries
        again."""
        was = blade.suspended
        blade.suspended = False
        if was:
            self._changed()
        contact = self.system.contact
        if contact is None or self._state is None:
            return
        if contact.intersecting(self._state.x, self.time):
            blade.suspended = True
            self._changed()

    def _organ_cut_step(self, t0: float, forces: dict) -> dict:
        """After a step t0 -> now: each blade cutting a FEM body cuts what it has swept
        (bodies/organ_cut.py), its cutting force joining ``forces``; each tearing body's cracks
        grow or a new one starts (bodies/organ_tear.py). Returns the step's {"cuts": {name:
        {"area_m2", "new_area_m2", "cells_cut", "pieces"}}} (a body's cracks as "body.tear",
        "body.tear2", ...)."""
        out = {}
        for blade in self.organ_cuts:
            blade.record(t0, self.time)  # an obstacle's blade, sampled as it went
            ahead = self._cuts_ahead(blade)
            cut = None if ahead else blade.swept(self.time)
            report = {"area_m2": blade.area, "new_area_m2": 0.0, "cells_cut": 0}
            force = np.zeros(3)
            done, blade.pending = blade.pending, None
            if done is None and cut is not None and t0 < blade.end + 1e-9 * self.time_step:
                done = self.cut_body(cut, body=blade.body, name=blade.name)
            if done is not None:
                new = max(done["area_m2"] - blade.area, 0.0)
                blade.area = done["area_m2"]
                report = {"area_m2": blade.area, "new_area_m2": new,
                          "cells_cut": done["cells_cut"], "pieces": done["pieces"]}  # fmt: skip
                force = blade.force(new, t0, self.time)
            report.update(self._body_totals(blade.body))
            if ahead:
                report["blade_contact"] = not blade.suspended
            if blade.obstacle is not None:  # and the bodies' contact force on the instrument
                force = force - np.asarray(forces.get(blade.obstacle, np.zeros(3)), dtype=float)
            forces[blade.name] = force.tolist()
            out[blade.name] = report
        for tear in self.organ_tears:
            out.update(self._grow_cracks(tear))
        return {"cuts": out}

    def _grow_cracks(self, tear) -> dict:
        """Grow the cracks of a tearing body (``BodyTearing``) where it is now, or start a new
        one when none grew (cut no new element). Returns each crack's report, as
        ``_organ_cut_step``'s."""
        b, c, _ = self.body_state(tear.body)
        done = {name: self.cut_body(surface, body=tear.body, name=name)
                for name, surface in tear.grow(b, c)}  # fmt: skip
        if not any(d["cells_cut"] for d in done.values()):
            b, c, _ = self.body_state(tear.body)
            new = tear.start(b, c)
            if new is not None:
                done[new[0]] = self.cut_body(new[1], body=tear.body, name=new[0])
        out = {}
        for k in range(max(len(tear.cracks), 1)):
            name = tear.crack_name(k)
            if name in done:
                report = {key: done[name][key] for key in ("area_m2", "cells_cut", "pieces")}
            else:
                area = 0.0 if b.cut_state is None else b.cut_state.area(name)
                report = {"area_m2": area, "cells_cut": 0}
            report.update(self._body_totals(tear.body))
            out[f"{tear.body}.{name}"] = report
        return out

    def _body_totals(self, name: str) -> dict:
        """A cut body's pieces (of material, crumbs not counted) and mass (kg; in 2D per metre
        of thickness) now, for every step's cut report: the uncut body's to round-off."""
        b = self.bodies[name]
        vn = None if b.cut_state is None else b.cut_state.vn
        mass = float(b.model.mass.lumped.sum()) / b.mesh.dim
        return {"pieces": 1 if vn is None else vn.n_pieces, "mass_kg": mass}
