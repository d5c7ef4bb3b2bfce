"""Adding, naming, finding and removing the bodies of a ``Simulation`` (a mixin, like
``simulation_setup.SetupCalls``): FEM meshes, meshless frame bodies, the connective tissue.
Body names are file stems of the output, so they are checked against each other's series."""

from __future__ import annotations

import functools
import re
from typing import TYPE_CHECKING

import numpy as np

from tissuesim import validate
from tissuesim.bodies.fem import FemBody
from tissuesim.energies.mass import MassKind
from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.mesh.mesh import Mesh
from tissuesim.time.state import State

if TYPE_CHECKING:
    from tissuesim.coupling.tissue import TissueBody

__all__ = ["BodyCalls", "RESERVED_NAMES"]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
#: a body's size (m, its largest extent) outside these is most likely in other units than
#: metres (a surface in millimetres read as metres is 1000x too large): warned, once
BODY_SIZE_RANGE = (1e-3, 5.0)
#: series the output writes besides the bodies'; no body may take these names
RESERVED_NAMES = ("cut", "summary", "forces", "manifest")


class BodyCalls:
    """Mixed into ``Simulation``."""

    _units_warned = False  # the units warning is given once per simulation

    def _check_units(self, name: str, points: np.ndarray) -> None:
        """Warn (once) of a body larger than a few metres or smaller than a millimetre: with
        SI moduli and gravity such a run goes on silently, off by factors of 1e3 and more."""
        import warnings

        if self._units_warned or not len(points):
            return
        size = float(np.max(np.ptp(np.asarray(points, dtype=float), axis=0)))
        low, high = BODY_SIZE_RANGE
        if low <= size <= high or not np.isfinite(size):
            return
        self._units_warned = True
        hint = (
            "a mesh in millimetres read as metres is 1000x too large: scale its points by 1e-3"
            if size > high
            else "a mesh in metres is meant here: scale its points if they are in other units"
        )
        side = f"larger than {high:g} m" if size > high else f"smaller than {low * 1e3:g} mm"
        warnings.warn(
            f"body {name!r} is {size:.3g} m across ({side}); tissuesim works in SI units (m, "
            f"Pa, kg/m^3, N): {hint} (this is said once)",
            UserWarning,
            stacklevel=3,
        )

    def _new_name(self, name: str, what: str, kind: str = "fem") -> str:
        """A body name that is valid as a file stem and clashes with no other body's output
        series (``<name>``, ``<name>_frames``, ``<name>_surface``, ``<name>_points``)."""
        from tissuesim.io.body_series import series_names

        if not isinstance(name, str) or not _NAME.fullmatch(name):
            raise InputError(
                f"{what} name {validate.short(name)} must be letters, digits, '_', '-' or '.', "
                "starting with a letter or digit (it names output files)"
            )
        taken = name in self.bodies or name in {o.name for o in self.obstacles}
        if taken or name in RESERVED_NAMES or (name == "tissue" != what):
            raise InputError(f"{what} name {name!r} is taken; choose another")
        mine = set(series_names(name, kind))
        if mine & set(self.visual_surfaces):
            raise InputError(f"{what} name {name!r} is a visual surface's series; choose another")
        for other in self.bodies.values():
            clash = mine & set(series_names(other.name, other.kind))
            if clash:
                raise InputError(
                    f"{what} name {name!r} would write the series {sorted(clash)[0]!r} that "
                    f"body {other.name!r} writes; choose another name"
                )
        if self._system is not None and self.history:
            raise RuntimeError(f"add {what}s before the first step")
        return name

    def _claim_force_name(self, name: str | None, default: str = "") -> str:
        """``name`` if it is new (else an error); None: ``default``, numbered if taken."""
        if name is None:
            name, k = default, 1
            while name in self._force_names:
                name, k = f"{default}_{k}", k + 1
        elif name in self._force_names:
            raise InputError(
                f"a support, grasper or spring set named {name!r} exists; give another name"
            )
        self._force_names.add(name)
        return name

    def _changed(self, body: str = "", what: str = "structure") -> None:
        """A body's set-up changed: ``structure`` rebuilds the system before the next step;
        ``prescribed`` / ``velocity`` also update the body's part of the state."""
        known = self._system is not None and body in self._system.names
        if self._state is not None and known and what in ("prescribed", "velocity"):
            j = self._system.index(body)
            b = self.bodies[body]
            x, v = self._state.x.copy(), self._state.v.copy()
            sc, st = self._system.config_slices[j], self._system.tangent_slices[j]
            if what == "prescribed":
                x[sc] = b.model.apply_prescribed(x[sc], self.time)
            else:
                v[st] = b.velocity
            self._state = State(self.time, x, v)
        if what != "velocity":  # a new velocity changes the state, not the system
            self._system_dirty = True

    def add_body(
        self,
        name: str,
        mesh: Mesh,
        material: Material,
        *,
        density: float | np.ndarray = 1000.0,
        mass: MassKind = "consistent",
        order: int | None = None,
        formulation: str = "displacement",
    ) -> FemBody:
        """A FEM body: a triangle or tetrahedral mesh (``mesh.box``, ``mesh.ellipsoid``,
        ``read_mesh``) of one material; density kg/m^3 (scalar or one per element).

        order: None (the mesh's), 1, or 2 (a linear mesh gets a node at every edge's midpoint;
        vertex indices are kept, point sets gain the midside nodes between their vertices).
        formulation: "displacement", or "mean_dilatation" for nearly incompressible laws
        (nu >= 0.45): the lambda term on element (P2) or vertex-patch (P1) volume averages,
        free of volumetric locking (``energies/mean_dilatation.py``)."""
        name = self._new_name(name, "body")
        if self.tissue is not None:
            raise InputError("add the organs before the tissue that connects them")
        if not isinstance(mesh, Mesh):
            raise InputError(f"add_body: mesh must be a tissuesim Mesh, not {validate.short(mesh)}")
        if not isinstance(material, Material):
            raise InputError(
                f"add_body: material must be a tissuesim material (make_material), not "
                f"{validate.short(material)}"
            )
        validate.choice(mass, "mass", ("consistent", "lumped"))
        validate.choice(formulation, "formulation", ("displacement", "mean_dilatation"))
        if order is not None:
            if isinstance(order, bool) or order not in (1, 2):
                raise InputError(f"order must be 1 or 2, not {validate.short(order)}")
            if order == 2 and not mesh.simplicial and mesh.order == 1:
                raise InputError(
                    f"add_body {name!r}: order 2 of {mesh.cell_type} cells is not available; "
                    "give a tetrahedral / triangle mesh for order 2, a quadratic one (box / "
                    "rectangle element = 'hex20', 'hex27', 'quad8', 'quad9'), or order 1"
                )
            if order == 2 and mesh.order == 1:
                from tissuesim.mesh.cells.elevate import elevate_mesh

                mesh = elevate_mesh(mesh)
            elif order == 1 and mesh.order == 2:
                raise InputError(
                    f"add_body {name!r}: order 1 was asked for but {mesh.source} has quadratic "
                    "elements; give a linear mesh or order = 2"
                )
        if self.explicit:
            mass = "lumped"  # the explicit update inverts the mass: it must be diagonal
        body = FemBody(
            name,
            mesh,
            material,
            density=density,
            mass=mass,
            formulation=formulation,
            backend=self.backend,
            claim_name=self._claim_force_name,
            changed=functools.partial(self._changed, name),
        )
        for g in self.gravity:
            body.add_gravity(g)
        self.bodies[name] = body
        self._check_units(name, mesh.points)
        self._changed()
        return body

    def add_frame_body(self, name: str, frames: np.ndarray, samples, material: Material, **kw):
        """A meshless body: frame origins (n, 3) (``grid_frames``, ``farthest_point_frames``),
        integration points with volumes (``sample_box``, ``sample_surface``, ...), any
        material; keywords of ``bodies.frames.FrameBody`` (density, frame_type "rigid" or
        "affine", shape "wendland" or "shepard", radius, radius_factor, min_frames,
        rotations, mass "full" or "lumped")."""
        from tissuesim.bodies.frames import FrameBody

        name = self._new_name(name, "body", "frames")
        body = FrameBody(
            name,
            frames,
            samples,
            material,
            backend=self.backend,
            claim_name=self._claim_force_name,
            changed=functools.partial(self._changed, name),
            time=lambda: self.time,
            **kw,
        )
        for g in self.gravity:
            body.add_gravity(g)
        self.bodies[name] = body
        self._changed()
        return body

    def add_tissue(self, material: Material, *, name: str = "tissue", **kw) -> TissueBody:
        """The connective tissue between the FEM bodies (``coupling/tissue.py``): integration
        points ``samples=``, or sampled between the organs (``thickness``, ``spacing``,
        ``region``); ``frames`` a count or (n, 3) origins; ``frame_type`` "affine" (default)
        or "rigid"; attached to every organ it touches (``attach_distance``,
        ``attachment_stiffness`` N/m per m^2)."""
        from tissuesim.coupling.tissue import TissueBody

        if self.tissue is not None:
            raise InputError("the scene has a tissue already; one tissue body per scene")
        name = self._new_name(name, "tissue", "tissue")
        organs = [(n, b.mesh) for n, b in self.bodies.items() if b.kind == "fem"]
        if any(m.dim != 3 for _, m in organs):
            raise InputError("the tissue joins 3D organs; a 2D body cannot take part")
        tissue = TissueBody(name, organs, material, backend=self.backend, **kw)
        for g in self.gravity:
            tissue.add_gravity(g)
        self.bodies[name] = self.tissue = tissue
        self._changed()
        return tissue

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

    def remove_body(self, name: str) -> None:
        """Take a body (and, for the tissue, its attachments and cuts) out, before the first
        step (e.g. to measure a scene without its tissue)."""
        if self.history:
            raise RuntimeError("remove_body must come before the first step")
        body = self.body(name)
        del self.bodies[name]
        self.visual_surfaces = {k: v for k, v in self.visual_surfaces.items() if v.body != name}
        if body is self.tissue:
            self.tissue = None
        self._state = None
        self._system = None
        self._changed()

    def body(self, name: str | None = None, kinds: tuple[str, ...] = ()):
        """The body called ``name``; None: the only body (of ``kinds``, if given)."""
        if name is not None:
            if name not in self.bodies:
                raise InputError(
                    f"unknown body {validate.short(name)}; bodies: {list(self.bodies)}"
                )
            b = self.bodies[name]
            if kinds and b.kind not in kinds:
                raise InputError(f"body {name!r} is a {b.kind} body; this needs {kinds}")
            return b
        candidates = [b for b in self.bodies.values() if not kinds or b.kind in kinds]
        if len(candidates) != 1:
            what = f"{'/'.join(kinds)} " if kinds else ""
            raise InputError(
                f"the simulation has {len(candidates)} {what}bodies "
                f"({[b.name for b in candidates]}); name one with body="
            )
        return candidates[0]
