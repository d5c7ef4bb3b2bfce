"""Rigid bodies of a Simulation (a mixin): ``add_rigid_body`` makes FEM bodies, or vertex sets
of them, move as one rigid body with six DOFs of its own in the same Newton solve (fixed,
prescribed or free; a dead force and moment), reported in ``forces()`` as its name (the force
the supports of its held DOFs apply, N) and ``<name>.moment`` (N m, about its centre)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from tissuesim import validate
from tissuesim.bodies.fem import vertex_indices
from tissuesim.errors import InputError
from tissuesim.rigid.body import DOF_NAMES, RigidModel

__all__ = ["RigidCalls", "RigidBodySpec", "SOFT_STIFFNESS"]

#: a prescribed rigid DOF in contact is pulled to its value by a spring this many times the
#: bodies' stiffness (force scale / length scale): it ends within about 1e-6 of the bodies'
#: own displacements of its value (measured in tests/febio/test_febio_rigid.py)
SOFT_STIFFNESS = 1e6


@dataclass(eq=False)
class RigidBodySpec:
    """What ``add_rigid_body`` was given: the linked (body, vertices) pairs, the centre (None:
    computed), held DOFs (index -> value function or None) and the loads."""

    name: str
    members: list[tuple[str, np.ndarray]]
    center: np.ndarray | None
    held: dict[int, Callable[[float], float] | None] = field(default_factory=dict)
    force: Callable[[float], np.ndarray] | None = None
    moment: Callable[[float], np.ndarray] | None = None


def _dof_index(name: object, what: str) -> int:
    if name not in DOF_NAMES:
        raise InputError(
            f"add_rigid_body: {what} names a DOF {validate.short(name)}; the DOFs are "
            f"{', '.join(DOF_NAMES)}"
        )
    return DOF_NAMES.index(name)


def _time_function(value, what: str) -> Callable[[float], float]:
    if callable(value):
        return value
    v = validate.real(value, what)
    return lambda t: v


def _vector_function(value, what: str) -> Callable[[float], np.ndarray] | None:
    if value is None:
        return None
    if callable(value):
        return lambda t: np.asarray(value(t), dtype=float).reshape(3)
    items = None
    if isinstance(value, np.ndarray | Sequence) and not isinstance(value, str):
        items = list(np.asarray(value, dtype=object).ravel())
    if items is None or len(items) != 3:
        raise InputError(f"add_rigid_body: {what} must be 3 numbers or functions of t")
    parts = [_time_function(v, what) for v in items]
    return lambda t: np.array([p(t) for p in parts])


class RigidCalls:
    """Mixed into ``Simulation``."""

    rigid_bodies: dict

    def add_rigid_body(
        self,
        name: str,
        bodies: Sequence[str] = (),
        *,
        vertices: Mapping[str, object] | None = None,
        center: Sequence[float] | None = None,
        fixed: Sequence[str] = (),
        prescribed: Mapping[str, float | Callable[[float], float]] | None = None,
        force: Sequence | Callable | None = None,
        moment: Sequence | Callable | None = None,
    ) -> str:
        """A rigid body named ``name``: the FEM ``bodies`` named move rigidly as a whole (an
        instrument, a bone, a platen: their mass is its mass, their surface its contact
        surface) and the ``vertices`` of other bodies ({body: vertices or a point set name})
        move with it (glued to it). Its DOFs ("x", "y", "z": the centre's translation; "rx",
        "ry", "rz": rotation about the global axes through the centre) are free unless
        ``fixed`` or ``prescribed`` ({dof: value (m or rad) or a function of t}); ``force``
        (N) and ``moment`` (N m, about the centre) act on it (3 numbers or functions of t, or
        one function of t giving 3). ``center`` (m): default the centre of mass of the
        ``bodies``, else the mean of the linked vertices."""
        if not isinstance(name, str) or not name.strip():
            raise InputError(f"add_rigid_body: name must be a text, not {validate.short(name)}")
        if name in self.rigid_bodies or name in self.bodies:
            raise InputError(f"add_rigid_body: a body named {name!r} exists; give another name")
        members: list[tuple[str, np.ndarray]] = []
        for b in bodies:
            body = self.body(b, ("fem",))
            if body.dim != 3:
                raise InputError(f"add_rigid_body: body {b!r} is 2D; rigid bodies are 3D")
            members.append((body.name, np.arange(body.mesh.n_points)))
        for b, which in (vertices or {}).items():
            body = self.body(b, ("fem",))
            if body.dim != 3:
                raise InputError(f"add_rigid_body: body {b!r} is 2D; rigid bodies are 3D")
            members.append((body.name, vertex_indices(which, body.mesh.n_points, "add_rigid_body")))
        if not members and center is None:
            raise InputError(
                f"add_rigid_body {name!r}: give the bodies it is made of, vertices that move "
                "with it, or (a body of no mass: a ground for joints) its center"
            )
        held: dict[int, Callable[[float], float] | None] = {}
        for dof in fixed:
            held[_dof_index(dof, "fixed")] = None
        for dof, value in (prescribed or {}).items():
            k = _dof_index(dof, "prescribed")
            if k in held:
                raise InputError(f"add_rigid_body: DOF {dof!r} is both fixed and prescribed")
            held[k] = _time_function(value, f"prescribed {dof}")
        c = None if center is None else validate.vector(center, "center", 3, unit="m")
        spec = RigidBodySpec(
            name,
            members,
            c,
            held,
            _vector_function(force, "force"),
            _vector_function(moment, "moment"),
        )
        for body, _ in members:
            b = self.bodies[body]
            if (
                b.cut_state is not None
                or any(c.body == body for c in self.organ_cuts)
                or any(t.body == body for t in self.organ_tears)
            ):
                raise InputError(
                    f"add_rigid_body {name!r}: body {body!r} is cut or cutting; a rigid body "
                    "names vertices a cut changes"
                )
        for body, v in members:  # held in their bodies; the system places them
            self.bodies[body].fix(v, name=f"{name}.{body}")
        self.rigid_bodies[name] = spec
        self._system_dirty = True
        return name

    def add_rigid_joint(
        self,
        kind: str,
        a: str,
        b: str,
        origin: Sequence[float],
        *,
        axis: Sequence[float] | None = None,
        transverse: Sequence[float] | None = None,
        rotation: float | Callable[[float], float] | None = None,
        translation: float | Callable[[float], float] | None = None,
        name: str | None = None,
        enforcement: dict | None = None,
    ) -> str:
        """A joint between rigid bodies ``a`` and ``b`` (``rigid/joints.py``): ``kind``
        "spherical", "revolute" (about ``axis``), "prismatic" (along ``axis``), "cylindrical"
        (along and about ``axis``) or "planar" (``axis`` its normal), at ``origin`` (m) with
        a ``transverse`` axis (the zero of ``rotation``); ``rotation`` (rad, about the axis)
        and ``translation`` (m, along it) prescribe the relative motion (numbers or functions
        of t). Held by an augmented Lagrangian to 1e-9 of the length scale, or by FEBio's rule
        with ``enforcement`` ({"penalty": N/m, "tolerance": ..., ``joints.Enforcement``'s
        fields}); its force and moment on ``b`` are reported as ``name`` and
        ``<name>.moment``."""
        from tissuesim.rigid.joints import RigidJoint

        for end in (a, b):
            if end not in self.rigid_bodies:
                raise InputError(
                    f"add_rigid_joint: {end!r} is not a rigid body; rigid bodies: "
                    f"{sorted(self.rigid_bodies) or 'none'}"
                )
        name = self._joint_name(name, kind)
        rot = None if rotation is None else _time_function(rotation, "rotation")
        tra = None if translation is None else _time_function(translation, "translation")
        c = validate.vector(origin, "origin", 3, unit="m")
        joint = RigidJoint(name, kind, a, b, c, axis, transverse, rot, tra,
                           enforcement=enforcement)  # fmt: skip
        self.rigid_joints.append(joint)
        self._system_dirty = True
        return name

    def add_rigid_spring(
        self,
        a: str,
        b: str,
        point_a: Sequence[float],
        point_b: Sequence[float],
        stiffness: float,
        *,
        free_length: float | None = None,
        name: str | None = None,
    ) -> str:
        """A linear spring (N/m) between ``point_a`` of rigid body ``a`` and ``point_b`` of
        ``b`` (m, at rest), of ``free_length`` (default their rest distance); its force on
        ``b`` is reported as ``name``."""
        from tissuesim.rigid.joints import RigidSpring

        for end in (a, b):
            if end not in self.rigid_bodies:
                raise InputError(f"add_rigid_spring: {end!r} is not a rigid body")
        name = self._joint_name(name, "spring")
        pa = validate.vector(point_a, "point_a", 3, unit="m")
        pb = validate.vector(point_b, "point_b", 3, unit="m")
        k = validate.real(stiffness, "stiffness", low=0.0, low_open=True, unit="N/m")
        self.rigid_joints.append(RigidSpring(name, a, b, pa, pb, k, free_length))
        self._system_dirty = True
        return name

    def _joint_name(self, name: str | None, kind: str) -> str:
        taken = {j.name for j in self.rigid_joints} | set(self.rigid_bodies) | set(self.bodies)
        if name is None:
            k = 1
            while f"{kind}_{k}" in taken:
                k += 1
            return f"{kind}_{k}"
        if name in taken:
            raise InputError(f"a joint, spring or body named {name!r} exists; give another name")
        return name

    def _joint_forces(self) -> dict[str, list[float]]:
        """Each joint's force and moment on its body b (minus its energy's gradient there)."""
        s, out = self.system, {}
        for j, (_, grad, _, _, _) in zip(s.joints, s.joint_terms(self._state.x, 1), strict=True):
            out[j.name] = (-grad[6:9]).tolist()
            out[f"{j.name}.moment"] = (-grad[9:12]).tolist()
        return out

    def _no_cut_of_rigid(self, body: str, what: str) -> None:
        """A body that is (part of) a rigid body or glued to one is never cut: its vertices,
        which the rigid body names, would be others after the cut."""
        for spec in self.rigid_bodies.values():
            if any(b == body for b, _ in spec.members):
                raise InputError(
                    f"{what}: body {body!r} moves with rigid body {spec.name!r}; a cut would "
                    "change the vertices it names: cut another body, or leave the rigid body out"
                )

    def _rigid_models(self, names: list[str]) -> tuple[list, list]:
        """(RigidModel per rigid body, (body index, vertices, rigid index) per member) for a
        system of the FEM bodies ``names``."""
        models, members = [], []
        for k, spec in enumerate(self.rigid_bodies.values()):
            mine = [(names.index(b), v) for b, v in spec.members if b in names]
            center = spec.center
            if center is None:
                center = self._rigid_center(spec)
            models.append(RigidModel(spec.name, center, spec.held, spec.force, spec.moment))
            members += [(j, v, k) for j, v in mine]
        return models, members

    @staticmethod
    def _rigid_parts(old, state) -> dict:
        """The rigid blocks' (configuration, velocity, None) of the system being replaced,
        by "rigid:<name>", for the new one to start from."""
        if old is None or state is None:
            return {}
        slices = zip(old.rigid, old.rigid_config_slices, old.rigid_tangent_slices, strict=True)
        return {f"rigid:{r.name}": (state.x[sc], state.v[st], None) for r, sc, st in slices}

    def _soften_rigid(self, system) -> None:
        """With contact, prescribed rigid DOFs are pulled by stiff springs (rigid/body.py
        ``soft``): SOFT_STIFFNESS times the system's force scale over its length scale."""
        if system.contact is None or not system.rigid:
            return
        stiffness = SOFT_STIFFNESS * system.force_scale / system.length_scale
        for r in system.rigid:
            r.soft, r.length = stiffness, system.length_scale
        system.set_prescribed()

    def _rigid_center(self, spec: RigidBodySpec) -> np.ndarray:
        """The centre of mass of the bodies made rigid as a whole (their lumped vertex masses),
        else the mean of the linked vertices."""
        whole = [b for b, v in spec.members if len(v) == self.bodies[b].mesh.n_points]
        if whole:
            # the consistent mass' row sums: each vertex's share, exact mass and first moment
            w = np.concatenate([self.bodies[b].model.mass.row_sums[::3] for b in whole])
            points = [self.bodies[b].mesh.points for b in whole]
            return (np.concatenate(points) * w[:, None]).sum(axis=0) / w.sum()
        return np.concatenate([self.bodies[b].mesh.points[v] for b, v in spec.members]).mean(axis=0)

    def rigid_state(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(centre position (3,) m, rotation matrix (3, 3)) of rigid body ``name`` now."""
        if name not in self.rigid_bodies:
            raise InputError(
                f"no rigid body named {name!r}; rigid bodies: {sorted(self.rigid_bodies)}"
            )
        s = self.system
        k = [r.name for r in s.rigid].index(name)
        z = self._state.x[s.rigid_config_slices[k]]
        return z[:3].copy(), z[3:12].reshape(3, 3).copy()

    def _rigid_forces(self, gradient: np.ndarray | None) -> dict[str, list[float]]:
        """Each rigid body's force (N) and moment (N m, about its centre) from its held DOFs'
        supports: the last solve's gradient at its six DOFs (zero on the free ones)."""
        s, out = self.system, {}
        slices = zip(s.rigid, s.rigid_config_slices, s.rigid_tangent_slices, strict=True)
        for r, sc, st in slices:
            g = np.zeros(6) if gradient is None or gradient.size != s.n_dofs else gradient[st]
            g = g + r.spring_forces(self._state.x[sc], self.time)  # a soft DOF's support
            out[r.name] = g[:3].tolist()
            out[f"{r.name}.moment"] = g[3:].tolist()
        if s.joints:
            out.update(self._joint_forces())
        return out
