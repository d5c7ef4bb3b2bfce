"""The set-up calls of ``Simulation`` that act on one body (named with ``body=``, or the only
body of the kind the call needs) or join two: each forwards to the body's own method
(``bodies/fem.py``, ``bodies/frames.py``, ``coupling/tissue.py``) or builds an interaction."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short, vector

if TYPE_CHECKING:
    from tissuesim.coupling.tissue import TissueBody

__all__ = ["SetupCalls", "CONTACT_MODES"]

#: ``set_contact(mode=...)`` and scene ``[contact] mode`` (``time/contact_step.py``)
CONTACT_MODES = ("auto", "accurate", "interactive", "barrier")


class SetupCalls:
    """Mixed into ``Simulation``."""

    # -- contact ------------------------------------------------------------------------------
    def set_contact(
        self,
        enabled: bool = True,
        *,
        dhat: float | None = None,
        stiffness: float | str | None = None,
        friction: float = 0.0,
        eps_v: float = 1e-3,
        friction_iterations: int = 2,
        surfaces: dict | None = None,
        pairs: Sequence | None = None,
        mode: str = "auto",
    ) -> None:
        """Barrier contact (IPC) between every FEM body's surface, itself and the obstacles
        (``contact/model.py``): ``dhat`` the activation distance (m; default 1e-3 of the
        scene's size), ``stiffness`` the barrier's kappa (Pa, fixed; default None or
        "adaptive": IPC's adaptive kappa from the largest Young's modulus E, within
        [E, 100 E], contact/barrier/stiffness.py);
        ``friction`` the Coulomb coefficient mu (IPC's smoothed friction, static
        below the sliding speed ``eps_v`` m/s, lagged over ``friction_iterations`` Newton
        solves per step). ``surfaces`` maps a body name to its contact surface, a facet set
        name (e.g. "zmax") or (k, 3) vertex indices (default: its whole boundary; leave out
        symmetry planes and faces that cannot touch). ``pairs``: ``ContactPair(a, b,
        enabled=, friction=)`` or ``{"bodies": [a, b], "enabled": ..., "friction": ...}``
        per pair of bodies / a body and an obstacle / a body with itself (a == b).
        ``mode`` (``time/contact_step.py``): "accurate" (the step's contacts predicted on the
        compliance, then the barrier's Newton from there: the barrier's answer and guarantee),
        "interactive" (the prediction, certified free of intersection by CCD, is the step;
        forces are its multipliers), "barrier" (the barrier's Newton alone), "auto" (the
        default: the barrier, interactive for steps with a budget). Contact needs no extra:
        the IPC Toolkit (ipctk) is installed with tissuesim."""
        import importlib.util

        from tissuesim.contact.model import ContactSettings
        from tissuesim.validate import real

        if enabled and importlib.util.find_spec("ipctk") is None:
            # ipctk is a dependency of tissuesim: missing only if it was uninstalled
            raise InputError(
                "contact needs the IPC Toolkit (ipctk, a dependency of tissuesim that is "
                "missing here): pip install ipctk"
            )
        if self.explicit and enabled:
            raise InputError("contact needs an implicit integrator (backward_euler, quasistatic)")
        if dhat is not None:
            dhat = real(dhat, "contact dhat", low=0.0, low_open=True, unit="m")
        if stiffness is not None and stiffness != "adaptive":
            if isinstance(stiffness, str):
                raise InputError(
                    f'contact stiffness must be a number (Pa) or "adaptive", not {stiffness!r}'
                )
            stiffness = real(stiffness, "contact stiffness", low=0.0, low_open=True, unit="Pa")
        from tissuesim.validate import integer

        friction = real(friction, "contact friction", low=0.0)
        eps_v = real(eps_v, "contact eps_v", low=0.0, low_open=True, unit="m/s")
        iterations = integer(friction_iterations, "contact friction_iterations", low=1, high=20)
        from tissuesim.validate import choice

        mode = choice(mode, "contact mode", CONTACT_MODES)
        settings = ContactSettings(
            dhat, stiffness, friction, eps_v, iterations, _surfaces(surfaces), _pairs(pairs), mode
        )
        self.contact = settings if enabled else None
        self._changed()

    def add_obstacle(
        self, name: str, surface, *, translation=None, rotation=None, friction=None
    ) -> str:
        """A kinematic rigid obstacle (``contact/obstacles.py``): a triangle ``surface``
        (``tissuesim.plane`` / ``sphere`` / ``capsule`` / ``cylinder``, ``read_surface``,
        ``frames.sampling.box_surface``) moved by ``translation`` (m) and ``rotation`` (a
        rotation vector about its centroid, rad), each a function of t or three numbers (a
        fixed offset from where the surface was made), with its own Coulomb ``friction``
        against every body (default the scene's). Its force on the bodies is reported as
        ``name`` (and its normal and friction parts as ``name.normal``, ``name.friction``).
        Switches contact on (``set_contact``) if it is off."""
        from tissuesim.contact.obstacles import Obstacle
        from tissuesim.frames.sampling import Surface

        if not isinstance(surface, Surface):
            raise InputError(
                f"add_obstacle: surface must be a Surface, not {type(surface).__name__}"
            )
        # a fixed place as numbers (a 3-vector, as a scene's constant expressions give) or a
        # function of t
        translation = _motion(translation, "translation", "m")
        rotation = _motion(rotation, "rotation", "rad")
        # a file stem clashing with no body, obstacle or internal series; then its force name
        if friction is not None:
            from tissuesim.validate import real

            friction = real(friction, f"obstacle {name!r} friction", low=0.0)
        name = self._claim_force_name(self._new_name(name, "obstacle"))
        self.obstacles.append(Obstacle(name, surface, translation, rotation, friction))
        if getattr(self, "contact", None) is None:
            self.set_contact()
        self._changed()
        return name

    def drive_obstacle(
        self, name: str, translation: Sequence[float] | None = None, rotation=None
    ) -> None:
        """Drive obstacle ``name`` live: its ``translation`` (m, from its rest place) and / or
        ``rotation`` (a rotation vector about its rest centroid, rad) at the end of the next
        step, reached on a straight line from where it is now. Call it between steps (from a
        haptic device, the mouse, a script); the next ``step()`` returns the obstacle's force
        in ``extra["forces"][name]``. The first call replaces the motion given to
        ``add_obstacle`` by a live one (contact/obstacles.py DrivenMotion)."""
        from dataclasses import replace

        from tissuesim.contact.obstacles import DrivenMotion

        names = [ob.name for ob in self.obstacles]
        if name not in names:
            known = ", ".join(names) or "none"
            raise InputError(f"drive_obstacle: no obstacle {name!r} (obstacles: {known})")
        k = names.index(name)
        ob = self.obstacles[k]
        t0, t1 = self.time, self.time + self.time_step
        changes = {}
        for key, value in (("translation", translation), ("rotation", rotation)):
            if value is None:
                continue
            motion = getattr(ob, key)
            if not isinstance(motion, DrivenMotion):
                now = np.zeros(3) if motion is None else np.asarray(motion(t0), dtype=float)
                motion = DrivenMotion(now)
                changes[key] = motion
            motion.set(value, t0, t1)
        if changes:
            ob = replace(ob, **changes)
            self.obstacles[k] = ob
            contact = None if self._system is None else self._system.contact
            if contact is not None:  # the built model keeps its mesh; only the motion changes
                contact.obstacles[k] = ob

    def attach(
        self,
        body: str,
        to: str,
        *,
        distance: float | None = None,
        stiffness: float | None = None,
        name: str | None = None,
    ):
        """Glue ``body`` to ``to`` where they touch, by a stiff penalty; the force ``to`` exerts
        on ``body`` is reported as ``name`` (default "<body>-<to>").

        Two FEM bodies (``coupling/tie.py``): ``body``'s boundary triangles whose vertices all
        lie within ``distance`` m of ``to`` (default 1e-3 of ``body``'s size); ``stiffness``
        N/m per m^2 of contact (default 250 times the stiffer shear modulus per median edge).
        A frame body and a FEM body (``coupling/frame_attachment.py``): the FEM body's
        boundary triangles facing the frame body's integration points within ``distance``
        (default 1.5 sample spacings); ``stiffness`` default 250 times the frame body's shear
        modulus per spacing (the tissue's rule)."""
        from tissuesim.coupling.tie import tie_bodies
        from tissuesim.coupling.tissue import ATTACHMENT_FACTOR

        a, b = self.body(body, ("fem", "frames")), self.body(to, ("fem", "frames"))
        if a is b:
            raise InputError(f"attach: a body cannot be attached to itself ({body!r})")
        if distance is not None and not (np.isfinite(distance) and distance > 0):
            raise InputError(f"attach: distance must be > 0 m, got {short(distance)}")
        if stiffness is not None and not (np.isfinite(stiffness) and stiffness > 0):
            raise InputError(f"attach: stiffness must be > 0 N/m per m^2, got {short(stiffness)}")
        if a.kind == b.kind == "frames":
            raise InputError(
                f"attach: {body!r} and {to!r} are both frame bodies; attach a frame body to a "
                "FEM body, or make them one frame body"
            )
        if "frames" in (a.kind, b.kind):
            return self._attach_frames(a, b, distance, stiffness, name)
        size = float(np.linalg.norm(np.ptp(a.mesh.points, axis=0)))
        if distance is None:
            distance = 1e-3 * size
        name = self._claim_force_name(name, f"{body}-{to}")
        edge = _median_boundary_edge(a.mesh)
        if stiffness is None:
            mu = max(a.model.material.mu, b.model.material.mu)
            stiffness = ATTACHMENT_FACTOR * mu / edge
        tie = tie_bodies(
            name, a.name, a.mesh, b.name, b.mesh, distance=distance, stiffness_per_area=stiffness
        )
        self.ties.append(tie)
        self._changed()
        return tie

    def _attach_frames(self, a, b, distance, stiffness, name):
        from tissuesim.coupling.frame_attachment import frame_attachment
        from tissuesim.coupling.tissue import ATTACHMENT_FACTOR

        frame, fem = (a, b) if a.kind == "frames" else (b, a)
        samples = frame.model.samples
        spacing = float(np.cbrt(np.median(samples.volumes)))
        distance = 1.5 * spacing if distance is None else float(distance)
        if stiffness is None:
            stiffness = ATTACHMENT_FACTOR * frame.model.material.mu / spacing
        name = self._claim_force_name(name, f"{a.name}-{b.name}")
        spec = frame_attachment(
            name,
            fem.name,
            fem.mesh,
            frame.name,
            samples,
            distance=distance,
            stiffness_per_area=stiffness,
        )
        spec.build(0, 1, frame.model)  # points the frames do not reach fail now
        spec_sign = 1.0 if a is fem else -1.0  # the force is reported on ``body``
        self.frame_attachments.append((spec, spec_sign))
        self._changed()
        return spec

    # -- set-up on one body (see bodies/fem.py, bodies/frames.py, coupling/tissue.py) ---------
    def add_dirichlet(
        self, vertices, displacement=None, components=None, *, body=None, name=None, active=None
    ):
        """Prescribe the displacement u = g(X, t) (m) of vertices of a FEM body.

        ``vertices``: vertex indices (e.g. ``select.vertices_on_plane(mesh, axis=0,
        value=-1.0)`` or ``mesh.point_sets["left"]``). ``displacement``: None clamps them, a
        vector (d,) holds a constant offset, a callable ``g(X, t)`` maps their rest positions
        (k, d) and the time (s) to displacements (k, d). ``components`` restricts the
        condition to some axes (``(0,)``: x only; the others stay free). ``active`` (t0, t1)
        in s holds it only for the steps that end after t0 and by t1 (None: always): the
        vertices are let go where they are after t1, and taken to g(X, t) from t0. Returns
        the name under which its reaction force (N) is reported per step (default
        ``"<body>.dirichlet_<k>"``, or ``name``; zero while it is not active).

        ``sim.add_dirichlet(left, lambda X, t: np.stack([0.1 * t + 0 * X[:, 0], 0 * X[:, 1]],
        axis=1))`` pulls the vertices ``left`` along x at 0.1 m/s."""
        return self.body(body, ("fem",)).add_dirichlet(
            vertices, displacement, components, name=name, active=active
        )

    def fix(self, *args, body: str | None = None, name: str | None = None) -> str:
        """Clamp vertices of a FEM body (every component held at its rest place); returns the
        support's name, under which its reaction force is reported.

        ``sim.fix(vertices, body="organ", name="table")``, like every per-body call (``body``
        may be left out when there is one FEM body); ``sim.fix("organ", vertices)``, the
        body first, is accepted too."""
        body, (vertices,) = _body_first("fix", args, 1, body)
        return self.body(body, ("fem",)).fix(vertices, name)

    def grasp(self, *args, body: str | None = None, stiffness=None, name=None, release=None):
        """Move vertices of a FEM body by ``displacement`` (a vector, m, or a function of t):
        prescribed (``stiffness`` None) or pulled through springs of ``stiffness`` (N/m per
        vertex), letting go at ``release`` (s; None: never). Returns the grasper; its force
        on the body is reported under its name.

        ``sim.grasp(vertices, displacement, body="organ")`` (``body`` may be left out when
        there is one FEM body); ``sim.grasp("organ", vertices, displacement)`` too."""
        body, (vertices, displacement) = _body_first("grasp", args, 2, body)
        return self.body(body, ("fem",)).grasp(
            vertices, displacement, stiffness=stiffness, name=name, release=release
        )

    def add_traction(self, facets, traction, *, body=None) -> None:
        """A dead traction on boundary facets of a FEM body: N/m on edges in 2D, Pa on
        triangles in 3D. ``facets``: (k, d) vertex indices of boundary facets (e.g.
        ``mesh.facet_sets["right"]`` or ``select.facets_on_plane``); ``traction``: a vector
        (d,) or a callable ``(X (k, d), t) -> (k, d)`` evaluated at the facets' vertices.
        ``sim.add_traction(mesh.facet_sets["zmax"], (0, 0, -100.0))`` presses the top face
        down at 100 Pa."""
        self.body(body, ("fem",)).add_traction(facets, traction)

    def add_follower_pressure(
        self, facets, pressure, *, body: str | None = None, name: str = "pressure"
    ) -> None:
        """A follower pressure (Pa) on boundary facets of a 3D body: it acts normal to the
        surface where it is now (FEBio's non-linear pressure). ``facets``: (k, 3) boundary
        triangles of P1 tetrahedra or (k, 4) quad faces of Q1 hexahedra, in any vertex order
        (they are oriented outward from the material: a positive p pushes on the body, on a
        cavity's wall it inflates it); ``pressure``: a number or a callable ``t -> p``.

        On a closed surface of triangles its work is p times the enclosed volume's change, one
        more energy of the step. On any other surface (the top face of a block, the inside of
        a vessel segment) it has no energy: each solve freezes it at a lag configuration and
        re-lags at the solution until it moves less than Newton's ``gradient_tolerance`` of
        itself, where it is the follower load (``energies/pressure_lag.py``); one that does
        not settle in 30 re-lags fails the step, which is then halved. Its energy term is the
        potential -f . x of the load frozen at the state, as a dead load's.
        ``sim.add_follower_pressure(mesh.facet_sets["zmax"], 1e3)`` presses a box's top face
        at 1 kPa."""
        self.body(body, ("fem",)).add_follower_pressure(facets, pressure, name)

    def add_nodal_forces(self, vertices, force, *, body=None) -> None:
        """Dead point loads (N) on vertices of a FEM body: a vector (d,) on each vertex, (k, d)
        per vertex, or a callable ``t -> (k, d)``. ``sim.add_nodal_forces(tip, (0, 0, -0.1))``
        hangs 0.1 N on every vertex of ``tip``."""
        self.body(body, ("fem",)).add_nodal_forces(vertices, force)

    def add_body_force(self, force_density, *, body=None) -> None:
        """A body force per unit rest volume (N/m^3) on a FEM body: a vector (d,) or a callable
        ``(X (n, d), t) -> (n, d)``. For gravity use ``add_gravity`` (m/s^2, scaled by the
        density)."""
        self.body(body, ("fem",)).add_body_force(force_density)

    def add_gravity(self, acceleration: Sequence[float], *, body: str | None = None) -> None:
        """Gravity (m/s^2, one component per dimension): on ``body``, or with body None on
        every body (also those added later)."""
        if body is not None:
            self.body(body).add_gravity(acceleration)
            return
        g = vector(acceleration, "gravity", (2, 3), unit="m/s^2")
        dims = {b.dim for b in self.bodies.values()}
        if dims and {g.shape[0]} != dims:
            raise InputError(
                f"gravity must have {max(dims)} components (the bodies are {max(dims)}D), got "
                f"{g.shape[0]}"
            )
        for b in self.bodies.values():
            b.add_gravity(g)
        self.gravity.append(g)

    def set_damping(self, mass: float = 0.0, stiffness: float = 0.0, *, body=None) -> None:
        """Rayleigh damping C = mass M + stiffness K (``mass`` alpha in 1/s, ``stiffness``
        beta in s) on a FEM body, or with body None on every FEM body there is; each mode of
        angular frequency omega gets the damping ratio alpha / (2 omega) + beta omega / 2.
        Implicit integrators only (``energies/damping.py``); 0, 0 removes it."""
        from tissuesim import validate

        alpha = validate.real(mass, "damping mass (alpha)", low=0.0, unit="1/s")
        beta = validate.real(stiffness, "damping stiffness (beta)", low=0.0, unit="s")
        if self.explicit and (alpha or beta):
            raise InputError(
                "Rayleigh damping needs an implicit integrator (backward_euler or quasistatic): "
                "it is a dissipation term of the step's minimisation"
            )
        bodies = [self.body(body, ("fem",))] if body is not None else self._active()
        for b in bodies:
            if b.kind == "fem":
                b.model.damping = (alpha, beta) if alpha or beta else None

    def set_velocity(self, velocity=None, *, linear=None, angular=None, body=None) -> None:
        """Initial velocity: FEM bodies (n, d) or (d,) m/s; frame bodies ``linear`` (3,)
        (``velocity`` is taken as linear) and ``angular`` (3,) rad/s."""
        b = self.body(body, ("fem", "frames"))
        if b.kind == "fem":
            b.set_velocity(velocity if velocity is not None else linear)
        else:
            lin = linear if linear is not None else velocity
            b.set_velocity(
                (0, 0, 0) if lin is None else lin, (0, 0, 0) if angular is None else angular
            )

    def fix_frames(self, frames, *, body=None, name=None) -> str:
        """Clamp frames of a frame body at their rest position and orientation. ``frames``:
        frame indices (``sim.frames_where(lambda X: X[:, 2] < 1e-9)``). Returns the name its
        reaction force (N) is reported under (default ``"<body>.fixed_frames"``). The frames'
        weights do not interpolate: to clamp a face, ``add_spring`` on its points holds it
        better than fixing the frames nearest to it."""
        return self.body(body, ("frames",)).fix_frames(frames, name)

    def prescribe_frames(self, frames, motion, *, body=None, name=None) -> str:
        """Move frames of a frame body: ``motion(t)`` (t in s) returns (displacement (3,) or
        (k, 3) in m, rotation vector (3,) or (k, 3) in rad), about each frame's own origin and
        relative to rest; None clamps them. Returns the name its reaction force (N) is
        reported under. ``sim.prescribe_frames(top, lambda t: ((0, 0, 0.01 * t), (0, 0, 0)))``
        lifts the frames ``top`` at 10 mm/s."""
        return self.body(body, ("frames",)).prescribe_frames(frames, motion, name=name)

    def frames_where(self, predicate: Callable, *, body=None) -> np.ndarray:
        """Indices of the frames of a frame body whose rest origins satisfy ``predicate``, a
        function of the rest origins (n, 3) returning a boolean (n,):
        ``sim.frames_where(lambda X: X[:, 2] < 1e-9)`` picks the frames on z = 0."""
        return self.body(body, ("frames",)).frames_where(predicate)

    def embed(self, name: str, points: np.ndarray, *, body=None):
        """Carry points (k, 3) (m; markers, sensor positions) with the frames of a frame body,
        by the frames' weights at their rest places. Their current positions are
        ``sim.embedded_positions(name)``. Returns the embedding."""
        return self.body(body, ("frames",)).embed(name, points)

    def embed_surface(self, surface, *, body=None):
        """A triangle surface (``frames.sampling.box_surface``, ``read_surface``) carried by the
        frames of a frame body: written as ``<body>_surface.pvd``, drawn as the body, and its
        contact surface when contact is on. Returns the embedding."""
        return self.body(body, ("frames",)).embed_surface(surface)

    def add_spring(self, points, stiffness, target=None, *, body=None, name=None):
        """Zero-length springs (``stiffness`` N/m each, a number or one per point) from points
        (k, 3) carried by the frames of a frame body to ``target(t) -> (k, 3)`` (m; None:
        their rest positions): a soft clamp, or an attachment to a moving organ or a
        grasper. Their pull (N) is reported per step as ``name``. Returns the spring set.
        ``sim.add_spring(root_points, 1e3)`` clamps a face softly."""
        return self.body(body, ("frames",)).add_spring(points, stiffness, target, name=name)

    def add_point_forces(self, points, force, *, body=None):
        """Dead forces (N) on points (k, 3) carried by the frames of a frame body: a vector
        (3,), one per point (k, 3), or a callable ``t -> (k, 3)``. Returns the embedding of
        the points."""
        return self.body(body, ("frames",)).add_point_forces(points, force)

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
        if threshold is not None:
            raise InputError(
                f"set_tearing: body {b.name!r} tears at a stress (stress=, Pa) or a stretch "
                "(stretch=), not at a strain threshold"
            )
        self.organ_tears = [t for t in self.organ_tears if t.body != b.name]
        self.organ_tears.append(BodyTearing(b.name, stress, stretch))


def _median_boundary_edge(mesh: Mesh) -> float:
    from tissuesim.mesh.queries.boundary import boundary_facets

    P = mesh.points[boundary_facets(mesh.simplices)]
    return float(np.median(np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2)))


def _surfaces(surfaces) -> dict:
    if surfaces is None:
        return {}
    if not isinstance(surfaces, dict) or not all(isinstance(k, str) for k in surfaces):
        raise InputError(
            "contact surfaces: give a table of body name -> facet set name (or vertex "
            f"triangles), e.g. {{'block': 'zmax'}}, not {short(surfaces)}"
        )
    return dict(surfaces)


def _pairs(pairs) -> tuple:
    from tissuesim.contact.pairs import ContactPair

    if pairs is None:
        return ()
    if isinstance(pairs, (str, dict)) or not isinstance(pairs, Sequence):
        raise InputError(f"contact pairs: give a list of pairs, not {short(pairs)}")
    out = []
    for item in pairs:
        if isinstance(item, ContactPair):
            out.append(item)
            continue
        if not isinstance(item, dict) or set(item) - {"bodies", "enabled", "friction"}:
            raise InputError(
                "contact pairs: each is ContactPair(a, b, ...) or a table with keys bodies, "
                f"enabled, friction, not {short(item)}"
            )
        names = item.get("bodies")
        if not isinstance(names, (list, tuple)) or len(names) != 2:
            raise InputError(
                f"contact pairs: bodies must name two bodies (or a body twice, for its self "
                f"contact, or a body and an obstacle), not {short(names)}"
            )
        out.append(ContactPair(names[0], names[1], item.get("enabled", True), item.get("friction")))
    return tuple(out)


def _body_first(method: str, args: tuple, n: int, body: str | None) -> tuple[str | None, tuple]:
    """(body, the n other arguments) of a call given as (args...) or (body, args...)."""
    if len(args) == n + 1 and isinstance(args[0], str):
        if body is not None:
            raise InputError(f"{method}: the body is named twice ({args[0]!r} and body={body!r})")
        return args[0], args[1:]
    if len(args) != n:
        what = "vertices" if n == 1 else "vertices, displacement"
        raise InputError(
            f"{method}({what}, body=..., name=...) takes {n} positional argument"
            f"{'s' if n > 1 else ''} (or the body's name first), not {len(args)}"
        )
    return body, args


class _Fixed:
    """A motion that stays put: the numbers ``add_obstacle`` was given, at every t (a class,
    not a lambda, so that an obstacle pickles)."""

    def __init__(self, value: np.ndarray) -> None:
        self.value = value

    def __call__(self, t: float) -> np.ndarray:
        return self.value.copy()


def _motion(value, what: str, unit: str):
    """``add_obstacle``'s translation / rotation: None, a function of t, or three numbers."""
    if value is None or callable(value):
        return value
    if isinstance(value, str) or not hasattr(value, "__len__"):
        raise InputError(
            f"add_obstacle: {what} must be a function of t, three numbers ({unit}) or None, "
            f"not {short(value)}"
        )
    return _Fixed(vector(value, f"add_obstacle {what}", 3, unit=unit))
