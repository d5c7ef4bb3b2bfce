"""What ``Simulation`` tells about its bodies between steps: positions, fields, forces,
energies, the stability limit (name the body with ``body=`` when there are several); the
visual surfaces bodies carry for the output (``add_visual_surface``)."""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short

if TYPE_CHECKING:
    from tissuesim.bodies.visual_surface import VisualSurface

__all__ = ["BodyResults"]


class BodyResults:
    """Mixed into ``Simulation``."""

    # -- results of one body (name it with body= when there are several) ---------------------
    def _only(self, prop: str, kinds: tuple[str, ...], method: str):
        """The only body (of ``kinds``) for a one-body property; with several, an error that
        names the method taking body=."""
        try:
            return self.body(None, kinds)
        except InputError:
            names = [b.name for b in self.bodies.values() if not kinds or b.kind in kinds]
            what = f"{'/'.join(kinds)} " if kinds else ""
            raise InputError(
                f"sim.{prop} is for a simulation with one {what}body; this one has "
                f"{len(names)} ({names}): use sim.{method}(body=...)"
            ) from None

    @property
    def model(self):
        """The only body's model (``Model`` or ``FrameModel``); several: ``body(name).model``."""
        return self._only("model", (), "body").model

    @property
    def mesh(self) -> Mesh:
        """The only FEM body's rest mesh; several bodies: ``body(name).mesh``."""
        return self._only("mesh", ("fem",), "body").mesh

    def body_positions(self, body: str | None = None) -> np.ndarray:
        """Current positions: FEM vertices (n, d); frame bodies: integration points (q, 3)."""
        b, x, _ = self.body_state(body)
        if b.kind == "fem":
            return x.reshape(b.mesh.points.shape)
        return b.model.point_map.positions(x)

    def body_displacement(self, body: str | None = None) -> np.ndarray:
        """Current displacement of a FEM body's vertices from their rest places (n, d), m."""
        b = self.body(body, ("fem",))
        return self.body_positions(b.name) - b.mesh.points

    def body_velocity(self, body: str | None = None) -> np.ndarray:
        """Current velocity of a FEM body's vertices (n, d), m/s."""
        b, _, v = self.body_state(body, ("fem",))
        return v.reshape(b.mesh.points.shape)

    @property
    def positions(self) -> np.ndarray:
        """Current vertex positions (n, d) of the only FEM body (m); several bodies:
        ``body_positions(body=...)``."""
        return self.body_positions(self._only("positions", ("fem",), "body_positions").name)

    @property
    def displacement(self) -> np.ndarray:
        """Displacement (n, d) of the only FEM body (m); several: ``body_displacement``."""
        return self.body_displacement(
            self._only("displacement", ("fem",), "body_displacement").name
        )

    @property
    def velocity(self) -> np.ndarray:
        """Velocity (n, d) of the only FEM body (m/s); several: ``body_velocity``."""
        return self.body_velocity(self._only("velocity", ("fem",), "body_velocity").name)

    def cell_fields(self, body: str | None = None) -> dict[str, np.ndarray]:
        """Per element of a FEM body: J, green_strain, cauchy_stress, von_mises,
        energy_density (``materials/measures.py``)."""
        b, x, _ = self.body_state(body, ("fem",))
        return b.cell_fields(x)

    def point_fields(self, body: str | None = None) -> dict[str, np.ndarray]:
        """At a frame body's integration points: positions, F and the continuum fields."""
        b, z, _ = self.body_state(body, ("frames", "tissue"))
        return b.point_fields(z)

    def embedded_positions(self, name: str = "surface", *, body: str | None = None):
        """Current positions (k, 3) of a frame body's embedded points ``name``."""
        b, z, _ = self.body_state(body, ("frames",))
        if name not in b.embedded:
            raise KeyError(f"no embedded points named {name!r}; known: {sorted(b.embedded)}")
        return b.embedded[name].positions(z)

    @property
    def frame_positions(self) -> np.ndarray:
        """Current origins (n, 3) of the only frame body's frames (m); several frame bodies:
        ``body_state(name)``."""
        b, z, _ = self.body_state(None, ("frames",))
        return b.model.frame_type.split(z)[0].copy()

    @property
    def frame_rotations(self) -> np.ndarray:
        """Current rotation matrices (n, 3, 3) of the only frame body's frames (affine frames:
        the rotation of their polar decomposition)."""
        b, z, _ = self.body_state(None, ("frames",))
        return b.model.rotations(z)

    @property
    def rest_frames(self) -> np.ndarray:
        """Rest origins (n, 3) of the only frame body's frames (m)."""
        return self.body(None, ("frames",)).rest_frames

    @property
    def n_frames(self) -> int:
        """Number of frames of the only frame body."""
        return self.body(None, ("frames",)).n_frames

    @property
    def surface(self):
        """The only frame body's embedded display surface (``embed_surface``), or None."""
        return self.body(None, ("frames",)).surface

    @property
    def embedded(self) -> dict:
        """The only frame body's embedded point sets by name (``embed``, ``embed_surface``:
        "surface"); their current positions: ``embedded_positions(name)``."""
        return self.body(None, ("frames",)).embedded

    # -- log tables (io/logfiles.py) ------------------------------------------------------------
    def add_logfile(
        self,
        kind: str,
        data: list[str],
        *,
        body: str | None = None,
        items: Any = None,
        ids: Any = None,
        file: str | None = None,
    ):
        """Ask a run with output for a CSV table, FEBio's ``<logfile>`` request: ``kind``
        "node_data" (vertices) or "element_data" (cells) of FEM body ``body``, or
        "rigid_body_data" (the rigid bodies in the order they were added; ``body`` unused), the
        variables
        ``data`` by FEBio's names (``ux``, ``Rx``, ``sx``, ``E1``, ``J``, ...: ``io/logfiles.py``),
        for the mesh rows ``items`` (None: all), labelled ``ids`` in the table (default: the
        rows + 1), written as ``file`` in the output directory (default ``<kind>_<n>.csv``)
        at every frame the run writes. Returns the checked request."""
        from tissuesim.io.logfiles import make_request

        taken = {r.file for r in self.logfiles}
        if kind == "rigid_body_data":
            if not self.rigid_bodies:
                raise InputError("rigid_body_data: the simulation has no rigid bodies")
            request = make_request(kind, data, "", len(self.rigid_bodies), items, ids, file, taken)
            self.logfiles.append(request)
            return request
        b = self.body(body, ("fem",))
        n = b.mesh.n_points if kind == "node_data" else b.mesh.n_cells
        request = make_request(kind, data, b.name, n, items, ids, file, taken)
        self.logfiles.append(request)
        return request

    # -- visual surfaces (bodies/visual_surface.py) -------------------------------------------
    def add_visual_surface(
        self,
        surface: Any,
        *,
        body: str | None = None,
        name: str | None = None,
        max_outside: float | None = None,
    ) -> VisualSurface:
        """Carry a fine triangle surface (in 2D a polyline) with FEM body ``body`` (SOFA's
        barycentric mapping): ``surface`` a file (STL, OBJ, PLY, any meshio reads), a
        ``Surface`` or a (points, cells) pair, at the body's rest place. It is embedded once
        in the body's elements; points outside the mesh (up to ``max_outside`` m, default one
        element) are carried by the closest element with extrapolated coordinates. It moves
        with the body, is written as the series ``name`` (default ``<body>_visual``) with
        ``displacement`` on its rest points, and is drawn instead of the body's coarse surface
        in the 3D pictures. No mechanics: no mass, stiffness or contact. A body that is cut
        or tears cannot carry one. Returns the VisualSurface."""
        from tissuesim.bodies.visual_surface import make_visual_surface

        b = self.body(body, ("fem",))
        self._no_cut_with_visual(b.name, "add_visual_surface", adding=True)
        name = f"{b.name}_visual" if name is None else name
        self._visual_name(name)
        visual = make_visual_surface(name, b.name, b.mesh, surface, max_outside)
        self.visual_surfaces[name] = visual
        return visual

    def visual_positions(self, name: str) -> np.ndarray:
        """Current positions (q, d) of visual surface ``name`` (``add_visual_surface``)."""
        if name not in self.visual_surfaces:
            raise InputError(
                f"no visual surface named {name!r}; known: {sorted(self.visual_surfaces)}"
            )
        v = self.visual_surfaces[name]
        return v.positions(self.body_positions(v.body))

    def _visual_name(self, name: Any) -> None:
        """A visual surface's series name: a file stem no body, obstacle, internal series or
        other visual surface writes."""
        from tissuesim.io.series.bodies import series_names
        from tissuesim.simulation.bodies import _NAME, RESERVED_NAMES

        if not isinstance(name, str) or not _NAME.fullmatch(name):
            raise InputError(
                f"visual surface name {short(name)} must be letters, digits, '_', '-' or '.', "
                "starting with a letter or digit (it names output files)"
            )
        taken = {s for b in self.bodies.values() for s in series_names(b.name, b.kind)}
        taken |= {o.name for o in self.obstacles} | set(RESERVED_NAMES) | {"tissue"}
        if name in taken or name in self.visual_surfaces:
            raise InputError(
                f"visual surface name {name!r} is taken (a body, obstacle, series or visual "
                "surface writes it); choose another with name="
            )

    def _no_cut_with_visual(self, body: str, what: str, adding: bool = False) -> None:
        """A body carrying a visual surface is never cut (the surface's triangles would bridge
        the opening and hide the cut), nor is a visual surface given to a body that is."""
        if adding:
            b = self.bodies[body]
            cutters = [c.name for c in self.organ_cuts if c.body == body]
            cutters += [f"{body}.tear" for t in self.organ_tears if t.body == body]
            if b.cut_state is not None:
                cutters.append("cut_body")
            if cutters:
                raise InputError(
                    f"{what}: body {body!r} is cut ({cutters[0]}); a visual surface does not "
                    "follow a cut (its triangles would bridge the opening and hide it): show "
                    "the cut body's own surface, or leave the cut out"
                )
            return
        carried = [v.name for v in self.visual_surfaces.values() if v.body == body]
        if carried:
            raise InputError(
                f"{what}: body {body!r} carries the visual surface {carried[0]!r}, which does "
                "not follow a cut (its triangles would bridge the opening and hide it): leave "
                "out the visual surface or the cut"
            )

    @property
    def graspers(self) -> list:
        """Every grasper of every FEM body (``grasp``), in the order they were added."""
        return [g for b in self.bodies.values() if b.kind == "fem" for g in b.graspers]

    def tissue_fields(self) -> dict[str, np.ndarray]:
        """At the alive tissue points: positions, F, the continuum fields, the largest
        principal strain and the points' stable ids ({} without tissue)."""
        if self.tissue is None or self.tissue.model is None:
            return {}
        return self.point_fields(self.tissue.name)

    def attachment_gap(self) -> float:
        """Largest distance (m) between where an organ and the tissue put an attachment
        point: the penalty's violation."""
        s, gap = self.system, 0.0
        for a in s.attachments:
            organ = s.bodies[a.organ]
            y = a.organ_positions(organ.mesh.simplices, s.body_config(self._state.x, a.organ))
            p = a.tissue.positions(s.body_config(self._state.x, a.tissue_body))
            gap = max(gap, float(np.linalg.norm(p - y, axis=1).max()))
        return gap

    def forces(self) -> dict[str, list[float]]:
        """Force (N, 3-vector) every support, prescribed set, grasper and spring set applies
        to its body at the current state (reactions from the last solve's gradient)."""
        s, g, out = self.system, self._last_gradient, {}
        for j, name in enumerate(s.names):
            gj = None if g is None or g.size != s.n_dofs else g[s.tangent_slices[j]]
            out.update(self.bodies[name].forces(s.body_config(self._state.x, j), gj, self.time))
        if s.rigid:
            out.update(self._rigid_forces(g))
        for t, r in zip(s.ties, s.tie_residuals(self._state.x), strict=True):
            out[t.name] = (-(t.stiffness[:, None] * r).sum(axis=0)).tolist()
        for name, sign, i in self._named_attachments:
            a = s.attachments[i]
            organ = s.bodies[a.organ]
            y = a.organ_positions(organ.mesh.simplices, s.body_config(self._state.x, a.organ))
            p = a.tissue.positions(s.body_config(self._state.x, a.tissue_body))
            # the frames pull the FEM body's points towards p: sign -1 reports the force on
            # the frame body instead
            out[name] = (sign * (a.stiffness[:, None] * (p - y)).sum(axis=0)).tolist()
        if s.penalty_contacts:
            out.update(self._penalty_forces(s, self._state.x))
        if s.contact is not None:
            t0, s.contact.time = s.contact.time, self.time
            for name, force in s.contact.obstacle_forces(self._state.x).items():
                out[name] = _as_3_vector(force)
            for name, force in s.contact.body_forces(self._state.x).items():
                # 2D contact gives 2-vectors; every force here is a 3-vector (z = 0 in 2D)
                out[name] = _as_3_vector(force)
            s.contact.time = t0
        return out

    def instrument_linearization(self, name: str):
        """Obstacle ``name``'s force at the last step's end and its stiffness for a small
        further translation (``contact/readout/haptics.py`` InstrumentLinearization: ``force`` N,
        ``stiffness`` N/m, ``force_at(d)``), from the last step's matrix through the kept
        factorisation: a haptic loop renders ``-force_at(d)`` at 1 kHz between steps."""
        from tissuesim.contact.readout.haptics import linearize_instrument
        from tissuesim.errors import InputError

        s = self.system
        names = [ob.name for ob in self.obstacles]
        if s.contact is None or name not in names:
            known = ", ".join(names) or "none"
            raise InputError(f"instrument_linearization: no obstacle {name!r} (obstacles: {known})")
        if self.explicit:
            raise InputError(
                "instrument_linearization needs an implicit integrator (backward_euler or "
                "quasistatic): explicit steps have no step matrix"
            )
        if s.last_step_energies is None:
            raise InputError(
                "instrument_linearization: take a step() first (it linearises the last one)"
            )
        solver = self._linear_solver()
        # its solves are not the next step's: the step's counts (record.extra["linear"]) stay
        kept = copy.copy(getattr(solver, "stats", None))
        t0, s.contact.time = s.contact.time, self.time
        try:
            return linearize_instrument(
                s, self._state.x, name, s.last_step_energies, solver, self.time
            )
        finally:
            s.contact.time = t0
            if kept is not None:
                solver.stats = kept

    def haptic_contact(self, name: str):
        """The last step's contact problem for instrument ``name``
        (``contact/predict/haptic.py`` HapticContact): ``force(d)`` (N) the force it exerts on
        the bodies after a further translation d (m) since the step, re-solved on the step's
        compliance (well under a millisecond at 1e4 tetrahedra), for a haptic device loop at
        1 kHz between steps; contacts that appear or vanish between steps change it without a
        jump. Needs the last step to be a predicted one (contact ``mode = "interactive"``, or
        "auto" with a budget); otherwise ``instrument_linearization``. Take a new one after
        every step (it is a snapshot: safe to use from the device's thread while the next step
        runs)."""
        from tissuesim.contact.predict.haptic import HapticContact
        from tissuesim.errors import InputError

        s = self.system
        names = [ob.name for ob in self.obstacles]
        if s.contact is None or name not in names:
            known = ", ".join(names) or "none"
            raise InputError(f"haptic_contact: no obstacle {name!r} (obstacles: {known})")
        kept = s.contact.predicted_forces
        if kept is None or not np.array_equal(kept[0], self._state.x):
            raise InputError(
                "haptic_contact: the last step was not a predicted one; set_contact(mode="
                '"interactive") (or step with a budget), or use instrument_linearization'
            )
        return HapticContact(s.contact, kept[1], name, self.time)

    def energies(self) -> dict[str, float]:
        """Energies (J) at the current state: elastic, kinetic, load_potential (-f . x) and the
        other terms (springs, grasper, attachment) summed over the bodies; with several
        bodies also each body's own, as "<body>.<term>"."""
        s, x, t = self.system, self._state.x, self.time
        acc = s.evaluate(x, 0, False, [self.bodies[n].step_energies(t, None, 1.0) for n in s.names])
        out: dict[str, float] = {"elastic": 0.0}
        for key, value in acc.terms.items():
            term = key.rsplit(".", 1)[-1]
            term = "load_potential" if term == "external" else term
            out[term] = out.get(term, 0.0) + value
            if "." in key:
                out[key.replace(".external", ".load_potential")] = value
        out["kinetic"] = (
            0.0 if self.integrator == "quasistatic" else s.kinetic_energy(x, self._state.v)
        )
        return out

    def min_J(self) -> float:
        """The smallest volume ratio J = det F over every element and integration point of
        every body at the current state: below 0, some element is inverted."""
        s = self.system
        return float(
            min(
                self.bodies[n].min_J(s.body_config(self._state.x, j)) for j, n in enumerate(s.names)
            )
        )

    def critical_time_step(self) -> float:
        """Explicit stability estimate (s): the smallest over the bodies (FEM: CFL h_min / c;
        frames: 2 / omega_max at the current configuration, springs included), lowered for
        the penalty springs of ties and attachments on FEM vertices: with omega_e = 2 / h_e
        of the stiffest body, omega^2 <= omega_e^2 + max_i sum_j |K_ij| / m_i (Gershgorin on
        the lumped masses; the sum of two PSD stiffnesses has at most the sum of their
        largest eigenvalues). The frame side of an attachment is not counted."""
        from tissuesim.frames.stability import frame_critical_time_step
        from tissuesim.time.integrators.stability import critical_time_step

        s, out = self.system, np.inf
        for j, name in enumerate(s.names):
            b = self.bodies[name]
            if b.kind == "fem":
                out = min(out, critical_time_step(b.model))
            else:
                z = s.body_config(self._state.x, j)
                out = min(out, frame_critical_time_step(b.model, z, self.time))
        penalty = self._penalty_frequency_squared()
        if penalty > 0.0:
            out = 2.0 / np.sqrt((2.0 / out) ** 2 + penalty)
        return float(out)

    def _penalty_frequency_squared(self) -> float:
        """Gershgorin bound of M^-1 K over FEM vertex DOFs for ties and attachments (1/s^2)."""
        import scipy.sparse as sp

        s = self.system
        rows = np.zeros(s.n_dofs)
        for t, (_, Gt) in zip(s.ties, s._tie_matrices, strict=True):
            K = Gt.T @ sp.diags(np.repeat(t.stiffness, 3)) @ Gt
            rows += np.asarray(abs(K).sum(axis=1)).ravel()
        for a in s.attachments:
            organ = s.bodies[a.organ]
            B = a.organ_matrix(organ.mesh.simplices, organ.mesh.n_points)
            K = abs(B.T @ sp.diags(a.stiffness) @ B)
            per_vertex = np.asarray(K.sum(axis=1)).ravel()
            start = s.tangent_slices[a.organ].start
            rows[start : start + 3 * organ.mesh.n_points] += np.repeat(per_vertex, 3)
        if not rows.any():
            return 0.0
        mass = np.full(s.n_dofs, np.inf)
        for j, b in enumerate(s.bodies):
            if not hasattr(b, "frame_type"):
                mass[s.tangent_slices[j]] = b.mass.lumped
        return float(np.max(rows / mass))


def _as_3_vector(force) -> list[float]:
    """A force as a 3-vector list (a 2D force gets z = 0, as the supports' do)."""
    f = np.zeros(3)
    v = np.asarray(force, dtype=float).ravel()
    f[: v.size] = v
    return f.tolist()
