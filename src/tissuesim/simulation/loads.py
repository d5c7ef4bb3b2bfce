"""The set-up calls of ``Simulation`` on one body (a mixin; the body named with ``body=``, or
the only body of the kind the call needs): supports, prescribed motions and graspers, loads and
gravity, damping, initial velocity; a frame body's fixed and moved frames, embedded points,
springs and point forces. Each forwards to the body's own method (``bodies/fem.py``,
``bodies/frames.py``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import vector

__all__ = ["LoadCalls"]


class LoadCalls:
    """Mixed into ``Simulation``."""

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
        triangles of P1 tetrahedra or (k, 4) quad faces of Q1 hexahedra or hexahedra20 (by
        their corners; a quad8 face's midside nodes join it), in any vertex order
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

    def add_springs(
        self,
        pairs,
        stiffness: float | None = None,
        *,
        tension_only: bool = False,
        force=None,
        measure: str = "elongation",
        scale: float = 1.0,
        anchors=None,
        rest_length=None,
        stiffness_scale=None,
        body: str | None = None,
        name: str = "springs",
    ):
        """Discrete springs between vertex pairs (k, 2) of a FEM body (a second vertex -1: a
        spring to the fixed point ``anchors[i]``, m), of rest lengths their rest distances:
        linear (``stiffness`` N/m; ``tension_only``: no force in compression) or with a
        ``force`` curve (an ``energies.node_springs.ForceCurve``, or an expression string of
        the measure ``x`` such as "2 * (exp(50 * x) - 1)", N, of the ``measure`` elongation
        (m), strain or stretch, times ``scale``). An energy with its exact
        gradient and Hessian (``energies/node_springs.py``). Returns the spring set.

        ``rest_length`` (m, one or one per spring) replaces the rest distances (FEBio's node
        distance target); ``stiffness_scale`` (t -> factor) multiplies the law at time t
        (FEBio's penalty on a load curve).

        ``sim.add_springs([[0, 9]], 50.0)`` joins vertices 0 and 9 by a 50 N/m spring."""
        from tissuesim.energies.node_springs import SpringLaw

        if (stiffness is None) == (force is None):
            raise InputError("add_springs: give a stiffness (N/m) or a force curve, not both")
        if isinstance(force, str):  # an expression of the measure x
            from tissuesim.energies.node_springs import ExpressionForce

            force = ExpressionForce(force, "add_springs force")
        if force is not None:
            law = SpringLaw("curve", curve=force, measure=measure, scale=float(scale))
        else:
            kind = "tension_only" if tension_only else "linear"
            law = SpringLaw(kind, stiffness=float(stiffness))
        return self.body(body, ("fem",)).add_springs(
            pairs, law, anchors=anchors, name=name, rest_length=rest_length, scale=stiffness_scale
        )

    def add_linear_constraint(self, terms, offset=0.0, *, stiffness=None, body=None, name=None):
        """Hold sum_i c_i u[v_i, a_i] = offset (m) over displacement components of a FEM
        body: ``terms`` [(vertex, axis, c_i), ...], c_i a number or a callable of t (FEBio's
        linear constraint: a parent DOF = the sum of child DOFs times their values), by a
        stiff penalty (``constraints/linear.py``; ``stiffness`` N/m, default 1e5 times the
        shear modulus times the median boundary edge). Returns the constraint.

        ``sim.add_linear_constraint([(5, 0, 1.0), (8, 0, -1.0)])``: vertex 5 moves along x
        as vertex 8 does."""
        return self.body(body, ("fem",)).add_linear_constraint(
            terms, offset, stiffness=stiffness, name=name
        )

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
