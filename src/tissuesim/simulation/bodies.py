"""Adding, naming, finding and removing the bodies of a ``Simulation`` (a mixin, as are the
other modules of this folder): FEM meshes, meshless frame bodies, the connective tissue. Body
names are file stems of the output, so they are checked against each other's series."""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from tissuesim import validate
from tissuesim.bodies.fem import FemBody
from tissuesim.bodies.regions import Region
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
        from tissuesim.io.series.bodies import series_names

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
        material: Material | None = None,
        *,
        density: float | np.ndarray = 1000.0,
        mass: MassKind = "consistent",
        order: int | None = None,
        formulation: str = "displacement",
        regions: Mapping[str, Region | tuple] | None = None,
    ) -> FemBody:
        """A FEM body: a triangle or tetrahedral mesh (``mesh.box``, ``mesh.ellipsoid``,
        ``read_mesh``) of one material; density kg/m^3 (scalar or one per element).

        regions: several materials in one body sharing its vertices, {name: (cells,
        material)} or {name: Region(cells, material, formulation, density)}, cells a cell
        set's name or cell indices; the cells no region names keep ``material`` (region
        "default"). Each region has its own formulation and density (None: the body's).

        order: None (the mesh's), 1, or 2 (a linear mesh gets a node at every edge's midpoint;
        vertex indices are kept, point sets gain the midside nodes between their vertices).
        formulation: "displacement", or "mean_dilatation" for nearly incompressible laws
        (nu >= 0.45): the lambda term on element (P2) or vertex-patch (P1) volume averages,
        free of volumetric locking (``energies/mean_dilatation.py``); "shell" for hexahedron20
        cells read as FEBio's quad8 shells (``solid_shell`` on quad8 faces;
        ``kinematics/shell.py``)."""
        name = self._new_name(name, "body")
        if self.tissue is not None:
            raise InputError("add the organs before the tissue that connects them")
        if not isinstance(mesh, Mesh):
            raise InputError(f"add_body: mesh must be a tissuesim Mesh, not {validate.short(mesh)}")
        if (
            regions is None
            and not isinstance(material, Material)
            or not (material is None or isinstance(material, Material))
        ):
            raise InputError(
                f"add_body: material must be a tissuesim material (make_material), not "
                f"{validate.short(material)}"
            )
        validate.choice(mass, "mass", ("consistent", "lumped", "element_rule"))
        validate.choice(formulation, "formulation", ("displacement", "mean_dilatation", "shell"))
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

                mesh = elevate_mesh(mesh)  # the cells keep their order: regions hold
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
            regions=regions,
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
