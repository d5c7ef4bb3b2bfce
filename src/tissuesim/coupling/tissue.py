"""The connective tissue between organs: a frame-based body sampled between FEM bodies,
attached to them, that blades cut and strain tears.

``TissueBody`` is what ``Simulation.add_tissue`` adds. Its integration points are sampled
between the organs (``layer.sample_between``) or given; it is attached to every organ on the
boundary triangles facing it (``layer.contact_facets``) at points no farther apart than the
spacing, each barycentric in an organ tetrahedron (``attachment.py``: a penalty energy). Its
``FrameModel`` is rebuilt from the original points that are still alive whenever a cut or a
tear changes who acts where (``cutting.Dissection``); the frames keep their place in the state.
See docs/coupling.md for every choice.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.coupling.attachment import Attachment
from tissuesim.coupling.cutting import CutTool, Dissection, sweep_triangles
from tissuesim.energies.loads import ExternalForce
from tissuesim.energies.mass import Inertia
from tissuesim.errors import InputError
from tissuesim.frames.loads import FrameGravity
from tissuesim.frames.model import FrameModel
from tissuesim.frames.placement import farthest_point_frames
from tissuesim.frames.sampling import IntegrationPoints
from tissuesim.materials.base import Material
from tissuesim.materials.measures import continuum_fields
from tissuesim.mesh.queries.boundary import facet_measures
from tissuesim.validate import short

__all__ = ["TissueBody", "ATTACHMENT_FACTOR", "MIN_J_AFTER_CUT"]

# default penalty of the attachment per unit contact area, in units of the tissue's shear
# modulus / sample spacing (about 100 E / spacing): stiff enough that the gap stays ~1% of the
# tissue's own stretch, soft enough for a well-conditioned Hessian
ATTACHMENT_FACTOR = 250.0
# after a cut or tear, tissue points the new weights leave this compressed (or inverted) are
# removed with the cut: their energy is infinite or near it
MIN_J_AFTER_CUT = 0.05


@dataclass(frozen=True, eq=False)
class _Contact:
    """Attachment points of the tissue on one organ (rest positions, organ cells,
    barycentric coordinates, stiffness N/m)."""

    organ: str
    points: np.ndarray
    cells: np.ndarray
    barycentric: np.ndarray
    stiffness: np.ndarray


def _facet_samples(
    points: np.ndarray, facets: np.ndarray, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """Attachment points on triangles: each split into n^2 similar sub-triangles with edges
    <= spacing, one point (with its area) at each sub-triangle's centroid."""
    P = points[facets]  # (m, 3, 3)
    edge = np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2).max(axis=1)
    area = facet_measures(points, facets)
    out_p, out_a = [], []
    for n in np.unique(np.maximum(1, np.ceil(edge / spacing)).astype(int)):
        sel = np.ceil(edge / spacing).clip(min=1).astype(int) == n
        # centroids of the n^2 sub-triangles in barycentric coordinates (up and down ones)
        i, k = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        up = i + k <= n - 1
        b_up = np.stack([i[up] + 1 / 3, k[up] + 1 / 3], axis=1) / n
        down = i + k <= n - 2
        b_down = np.stack([i[down] + 2 / 3, k[down] + 2 / 3], axis=1) / n
        b = np.concatenate([b_up, b_down])  # (n^2, 2)
        w = np.column_stack([1 - b.sum(axis=1), b])  # (n^2, 3)
        out_p.append(np.einsum("sv,mvi->msi", w, P[sel]).reshape(-1, 3))
        out_a.append(np.repeat(area[sel] / n**2, len(w)))
    return np.concatenate(out_p), np.concatenate(out_a)


class TissueBody:
    """The tissue layer; see the module docstring. ``organs``: (name, Mesh) of every FEM body
    at the time it is added."""

    kind = "tissue"
    dim = 3

    def __init__(
        self,
        name: str,
        organs: Sequence[tuple[str, object]],
        material: Material,
        *,
        samples: IntegrationPoints | None = None,
        thickness: float | None = None,
        spacing: float | None = None,
        region: Callable[[np.ndarray], np.ndarray] | None = None,
        frames: int | np.ndarray = 24,
        density: float = 1000.0,
        frame_type: str = "affine",
        shape: str = "wendland",
        radius_factor: float = 1.5,
        attach_distance: float | None = None,
        attachment_stiffness: float | None = None,
        backend: str = "auto",
    ) -> None:
        from tissuesim.coupling.layer import contact_facets, sample_between
        from tissuesim.mesh.queries.locate import closest_boundary_points

        if not organs:
            raise InputError("add the organs before the tissue that connects them")
        meshes = [m for _, m in organs]
        if samples is None:
            if thickness is None or spacing is None:
                raise InputError(
                    "add_tissue needs samples=, or thickness= and spacing= to sample the layer "
                    "between the organs"
                )
            samples = sample_between(meshes, thickness, spacing, region=region)
        if spacing is None:
            spacing = float(np.cbrt(np.median(samples.volumes)))
        if isinstance(frames, int | np.integer):
            if frames < 1 or frames > samples.n:
                raise InputError(
                    f"frames must be between 1 and the number of tissue points ({samples.n}), "
                    f"got {frames}"
                )
            frames = farthest_point_frames(samples.points, int(frames))
        if not (np.isfinite(density) and density > 0):
            raise InputError(f"tissue density must be > 0 kg/m^3, got {short(density)}")
        self.name = name
        self.material = material
        self.samples = samples
        self.frames = np.asarray(frames, dtype=float)
        self.density = float(density)
        self.frame_type = frame_type
        self.shape = shape
        self.radius_factor = float(radius_factor)
        self.spacing = float(spacing)
        self.attach_distance = float(1.5 * spacing if attach_distance is None else attach_distance)
        if attachment_stiffness is None:
            attachment_stiffness = ATTACHMENT_FACTOR * material.mu / spacing
        elif not (np.isfinite(attachment_stiffness) and attachment_stiffness > 0):
            raise InputError(
                f"attachment_stiffness must be > 0 N/m per m^2 of contact, got "
                f"{attachment_stiffness!r}; leave it out for 250 shear moduli / spacing"
            )
        self.attachment_stiffness = float(attachment_stiffness)
        self.backend = backend
        self.gravity: list[np.ndarray] = []
        self.cuts: list[CutTool] = []
        self.tear_threshold: float | None = None
        self.contacts: list[_Contact] = []
        for organ, mesh in organs:
            facets = contact_facets(mesh, samples.points, self.attach_distance)
            if len(facets) == 0:
                continue
            points, area = _facet_samples(mesh.points, facets, spacing)
            where = closest_boundary_points(mesh, points)
            self.contacts.append(
                _Contact(
                    organ,
                    where.positions,
                    where.cells,
                    where.barycentric,
                    self.attachment_stiffness * area,
                )
            )
        if not self.contacts:
            raise InputError(
                f"the tissue touches no organ: no organ boundary triangle lies within "
                f"attach_distance {self.attach_distance:g} m of a tissue point; increase "
                "attach_distance or move the tissue against the organs"
            )
        self.dissection = Dissection(
            len(self.frames), samples.n, [len(c.points) for c in self.contacts]
        )
        self.radii = None
        self.model: FrameModel | None = self._build_model()
        self.radii = self.model.shapes.radii
        self.config = self.model.rest_config()
        self.velocity = np.zeros(self.model.n_dofs)
        self.cut_world: list[np.ndarray] = []  # swept triangles as cut, world coordinates
        self._rest_blades: dict[str, np.ndarray] = {}  # each tool's last blade, rest coordinates

    def __repr__(self) -> str:
        return f"TissueBody({self.name!r}, {self.samples.n} points, {len(self.frames)} frames)"

    # -- set-up ------------------------------------------------------------------------------
    def add_gravity(self, acceleration) -> None:
        g = np.asarray(acceleration, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputError(f"add_gravity: acceleration must be 3 finite numbers, not {short(g)}")
        self.gravity.append(g)
        if self.model is not None:
            self.model.loads.append(FrameGravity(g))

    def add_cut(
        self,
        blade: Callable[[float], np.ndarray],
        start: float,
        end: float,
        *,
        kerf: float | None = None,
        name: str = "cut",
    ) -> CutTool:
        """Dissect: ``blade(t)`` -> (k, 3) polyline (m) swept through the tissue for
        start <= t <= end; kerf (m, default: half the tissue's sample spacing) is the width
        of material it removes."""
        if not end > start:
            raise InputError(f"cut {name!r}: end ({end}) must be after start ({start})")
        if any(c.name == name for c in self.cuts):
            raise InputError(f"a cut named {name!r} exists; give another name")
        if kerf is None:
            kerf = 0.5 * float(np.cbrt(np.median(self.samples.volumes)))
        elif not (np.isfinite(kerf) and kerf >= 0):
            raise InputError(
                f"cut {name!r}: kerf must be >= 0 m (the width the blade removes), "
                f"got {short(kerf)}"
            )
        tool = CutTool(blade, float(start), float(end), float(kerf), name)
        tool.positions(start)  # a malformed blade fails here
        self.cuts.append(tool)
        return tool

    def set_tearing(self, threshold: float) -> None:
        """Tissue integration points whose largest principal Green strain passes
        ``threshold`` are removed after the step (tearing)."""
        if not (np.isfinite(threshold) and threshold > 0):
            raise InputError(f"tearing threshold must be a strain > 0, got {short(threshold)}")
        self.tear_threshold = float(threshold)

    # -- the frame model and its attachments -------------------------------------------------
    def _build_model(self) -> FrameModel | None:
        d = self.dissection
        ids = np.flatnonzero(d.alive)
        if ids.size == 0:
            return None
        s = self.samples
        return FrameModel(
            self.frames,
            IntegrationPoints(s.points[ids], s.volumes[ids], s.source),
            self.material,
            density=self.density,
            frame_kind=self.frame_type,
            shape=self.shape,
            radius=self.radii,
            radius_factor=self.radius_factor,
            backend=self.backend,
            loads=[FrameGravity(g) for g in self.gravity],
            keep_pair=d.point_filter(),
            allow_orphans=True,
        )

    def follow_organ_cut(
        self, organ: str, remap: Callable[[np.ndarray, np.ndarray], np.ndarray]
    ) -> None:
        """Organ ``organ`` was cut: each attachment point on it moves to the cell of the new
        mesh that ``remap(cells, barycentric)`` gives (the copy on its side of the cut; its
        barycentric coordinates stay, as a copy keeps its element's shape)."""
        self.contacts = [
            dataclasses.replace(c, cells=remap(c.cells, c.barycentric)) if c.organ == organ else c
            for c in self.contacts
        ]

    def attachments(self, organ_index: Callable[[str], int], tissue_index: int) -> list:
        """The attachments still alive, organs by their system index."""
        out = []
        d = self.dissection
        for slot, c in enumerate(self.contacts):
            ids = np.flatnonzero(d.attachment_alive[slot])
            if ids.size == 0:
                continue
            emb = self.model.embed(
                c.points[ids], "attachment point", keep_pair=d.attachment_filter(slot)
            )
            out.append(
                Attachment(
                    organ_index(c.organ),
                    c.points[ids],
                    c.cells[ids],
                    c.barycentric[ids],
                    c.stiffness[ids],
                    emb,
                    ids,
                    tissue_index,
                )
            )
        return out

    # -- per step ------------------------------------------------------------------------------
    def step_energies(self, t: float, z_pred: np.ndarray | None, h: float) -> list:
        energies = [] if z_pred is None else [Inertia(self.model.mass, z_pred, h)]
        energies.append(ExternalForce(self.model.external_force(t)))
        return energies

    @staticmethod
    def forces(z, gradient, t) -> dict:
        return {}

    def point_fields(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """At the alive integration points: positions, F, the continuum fields
        (``materials/measures.py``), the largest principal strain and the points' ids."""
        if self.model is None:
            return {}
        m = self.model
        F = m.kinematics.deformation_gradients(z)
        fields = continuum_fields(m.material, F)
        fields["positions"] = m.point_map.positions(z)
        fields["F"] = F
        fields["max_principal_strain"] = np.linalg.eigvalsh(fields["green_strain"])[:, -1]
        fields["ids"] = np.flatnonzero(self.dissection.alive)
        return fields

    def min_J(self, z: np.ndarray) -> float:
        return float(np.linalg.det(self.model.kinematics.deformation_gradients(z)).min())

    @property
    def cut_surface(self) -> np.ndarray:
        """Triangles (m, 3, 3) the blades swept through so far, in world coordinates as cut."""
        return np.concatenate(self.cut_world) if self.cut_world else np.zeros((0, 3, 3))

    def topology(self, z: np.ndarray, t0: float, t1: float, rebuild: Callable[[], np.ndarray]):
        """Cuts swept during (t0, t1] and tearing at t1. ``rebuild()`` remakes the tissue's
        model and the system when something changed and returns the tissue's configuration
        (unchanged: frames stay where they are, only who acts where changes; None when no
        point is left). Returns the step's events."""
        d = self.dissection
        events = []
        for tool in self.cuts:
            last = self._rest_blades.get(tool.name)
            count = None if last is None else len(last)
            world = tool.blades(t0, t1, self.spacing, count)
            if world is None:
                continue
            rest = self._to_rest(z, world.reshape(-1, 3)).reshape(world.shape)
            if last is not None:
                # continue the cut surface from where the last step left it: the rest-space
                # map changes between steps, and a seam would leave a strip uncut
                rest[0] = last
            self._rest_blades[tool.name] = rest[-1]
            triangles = sweep_triangles(rest)
            # the part of the sweep that passes beyond the tissue cuts nothing
            pts = self.samples.points
            lo, hi = pts.min(axis=0) - self.spacing, pts.max(axis=0) + self.spacing
            inside = np.all((triangles.max(axis=1) >= lo) & (triangles.min(axis=1) <= hi), axis=1)
            triangles = triangles[inside]
            self.cut_world.append(sweep_triangles(world))
            if not len(triangles):
                events.append({"kind": "cut", "tool": tool.name, "time": t1})
                continue
            report = d.cut(
                triangles,
                tool.kerf,
                self.frames,
                self.samples.points,
                [c.points for c in self.contacts],
                self.radii,
            )
            events.append({"kind": "cut", "tool": tool.name, "time": t1, **report})
        if self.tear_threshold is not None and self.model is not None:
            f = self.point_fields(z)
            torn = f["ids"][f["max_principal_strain"] > self.tear_threshold]
            if torn.size:
                events.append({"kind": "tear", "time": t1, **d.tear(torn)})
        keys = ("removed_points", "severed_pairs", "retired_frames", "removed_attachments")
        changed = any(e.get(k, 0) for e in events for k in keys)
        if not (changed or any(e["kind"] == "tear" for e in events)):
            return events  # the blade is still outside the tissue: nothing to rebuild
        inverted, report = 0, {}
        for _ in range(10):
            more = d.consolidate(
                self.frames,
                self.samples.points,
                [c.points for c in self.contacts],
                self.radii,
                self.shape,
            )
            report = {k: report.get(k, 0) + v for k, v in more.items()}
            self.model = self._build_model()
            z = rebuild()
            if self.model is None:  # every point is gone: the organs go on alone
                break
            # renormalised weights change F at once; a point they leave inverted (at the lips
            # of a cut) has no finite neo-Hookean energy: it is removed like the kerf
            f = self.point_fields(z)
            if not f:
                break
            bad = f["ids"][~((f["J"] > MIN_J_AFTER_CUT) & np.isfinite(f["energy_density"]))]
            if not bad.size:
                break
            d.alive[bad] = False
            inverted += int(bad.size)
        events[-1].update(report)
        events[-1]["inverted_points_removed"] = inverted
        return events

    def _to_rest(self, z: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Rest positions of world points w (k, 3) in the tissue: X_s + F_s^-1 (w - p_s) with
        s the nearest integration point now (first-order inverse of the deformation)."""
        from scipy.spatial import cKDTree

        m = self.model
        F = m.kinematics.deformation_gradients(z)
        p = m.point_map.positions(z)
        _, s = cKDTree(p).query(w)
        dX = np.linalg.solve(F[s], (w - p[s])[:, :, None])[:, :, 0]
        return m.samples.points[s] + dX

    def describe(self) -> dict:
        return {
            "kind": "tissue",
            "material": repr(self.material),
            "density": self.density,
            "integration_points": self.samples.n,
            "alive_points": int(self.dissection.alive.sum()),
            "volume": float(self.samples.volume),
            "frames": len(self.frames),
            "frame_type": self.frame_type,
            "shape_functions": self.shape,
            "attachment": "penalty (zero-length springs, barycentric in organ tetrahedra)",
            "attachment_stiffness_per_area": self.attachment_stiffness,
            "attachment_points": {c.organ: int(len(c.points)) for c in self.contacts},
            "cuts": [
                {"name": c.name, "start": c.start, "end": c.end, "kerf": c.kerf} for c in self.cuts
            ],
            "tear_threshold": self.tear_threshold,
        }
