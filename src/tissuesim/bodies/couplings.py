"""The vertex couplings of a FEM body outside its cells (a mixin of ``FemBody``): discrete
springs between vertex pairs or to fixed points (``energies/node_springs.py``) and linear
constraints over displacement components (``constraints/linear.py``). Their vertex pairs
join the body's sparsity pattern: the body's model is made again with them (``_relink``)."""

from __future__ import annotations

import numpy as np

from tissuesim.errors import InputError
from tissuesim.model import Model
from tissuesim.validate import short

__all__ = ["VertexCouplings"]


class VertexCouplings:
    """Mixed into ``FemBody`` (its ``model``, ``mesh``, ``dim``, ``springs``,
    ``linear_constraints`` and ``_changed``)."""

    def add_springs(
        self, pairs, law, *, anchors=None, name: str = "springs", rest_length=None, scale=None
    ):
        """Discrete springs of ``law`` (``energies/node_springs.py`` SpringLaw) between vertex
        pairs (k, 2) of this body, a second vertex -1 for a spring to the fixed point
        ``anchors[i]`` (k, d); rest lengths from the rest mesh. The springs' blocks join the
        body's pattern (its model is made again). Returns the NodeSprings."""
        from tissuesim.energies.node_springs import NodeSprings

        P = np.asarray(pairs)
        if P.ndim != 2 or P.shape[1] != 2 or not np.issubdtype(P.dtype, np.integer):
            raise InputError(
                f"add_springs: pairs must be (k, 2) vertex indices, got {short(pairs)}"
            )
        n = self.mesh.n_points
        if np.any(P[:, 0] < 0) or np.any(P >= n) or np.any(P[:, 1] < -1):
            raise InputError(f"add_springs: a vertex index outside 0..{n - 1} in {short(pairs)}")
        X = self.mesh.points
        ends = X[np.maximum(P[:, 1], 0)]
        A = None
        if np.any(P[:, 1] < 0):
            A = np.asarray(anchors, dtype=float) if anchors is not None else None
            if A is None or A.shape != (len(P), self.dim) or not np.all(np.isfinite(A)):
                raise InputError(
                    f"add_springs: a pair with second vertex -1 needs anchors ({len(P)}, "
                    f"{self.dim}) finite points (m)"
                )
            ends = np.where(P[:, 1:] >= 0, ends, A)
        if np.any(P[:, 0] == P[:, 1]):
            raise InputError("add_springs: a spring joins a vertex to itself")
        rest = np.linalg.norm(ends - X[P[:, 0]], axis=1)
        if rest_length is not None:  # FEBio's node distance: its target, not the rest one
            rest = np.broadcast_to(np.asarray(rest_length, dtype=float), rest.shape).copy()
            if np.any(rest < 0) or not np.all(np.isfinite(rest)):
                raise InputError("add_springs: rest_length must be >= 0 m")
        springs = NodeSprings(P, rest, law, A, name, self.dim, scale)
        self.springs.append(springs)
        self._relink()
        return springs

    def add_linear_constraint(self, terms, offset=0.0, *, stiffness=None, name=None):
        """sum_i c_i u[v_i, a_i] = offset over displacement components of this body, held by
        a stiff penalty (``constraints/linear.py``): ``terms`` [(vertex, axis, c_i), ...],
        c_i a number or a callable t -> c_i, ``offset`` m (or a callable of t);
        ``stiffness`` N/m (default 1e5 times the shear modulus times the median boundary
        edge: the residual about 1e-5 of the displacements; see constraints/linear.py).
        Returns the constraint."""
        from tissuesim.constraints.linear import LinearConstraint
        from tissuesim.simulation.interactions import _median_boundary_edge

        try:
            vertices = np.array([int(v) for v, _, _ in terms])
            axes = np.array([int(a) for _, a, _ in terms])
        except (TypeError, ValueError):
            raise InputError(
                f"add_linear_constraint: terms must be (vertex, axis, coefficient), got "
                f"{short(terms)}"
            ) from None
        n = self.mesh.n_points
        if vertices.size == 0 or np.any(vertices < 0) or np.any(vertices >= n):
            raise InputError(f"add_linear_constraint: a vertex outside 0..{n - 1}")
        if np.any(axes < 0) or np.any(axes >= self.dim):
            raise InputError(f"add_linear_constraint: an axis outside 0..{self.dim - 1}")
        if stiffness is None:
            mu = self._model.material.mu  # the material a relink keeps: no relink here
            stiffness = 1e5 * mu * _median_boundary_edge(self.mesh)
        name = name or f"linear_constraint_{len(self.linear_constraints) + 1}"
        rest = self.mesh.points[vertices, axes]
        constraint = LinearConstraint(vertices, axes, tuple(c for _, _, c in terms), offset,
                                      float(stiffness), rest, self.dim, name)  # fmt: skip
        constraint.at(0.0)  # a coefficient that is not a number fails here, naming it
        self.linear_constraints.append(constraint)
        self._relink()
        return constraint

    def _relink(self) -> None:
        """The model is to be made again with the vertex pairs of the springs and linear
        constraints in its pattern: at its next use (``FemBody.model``), once for any
        number of couplings added before (made per coupling, mi19's 2421 constraints took
        570 s to set up)."""
        self._links_pending = True
        self._changed()

    def _linked_model(self, old: Model) -> Model:
        """``old`` made again with the couplings' vertex pairs in its pattern."""
        linked = [s.pairs[s.pairs[:, 1] >= 0] for s in self.springs]
        for c in self.linear_constraints:
            v = np.unique(c.vertices)
            linked.append(np.stack(np.meshgrid(v, v), axis=-1).reshape(-1, 2))
        linked = [p[p[:, 0] != p[:, 1]] for p in linked]
        model = Model(old.mesh, old.material, old.density, old.mass_kind, backend=old.backend,
                      formulation=old.formulation, links=np.vstack(linked),
                      regions=old.regions)  # fmt: skip
        model.loads, model.damping = old.loads, old.damping
        model.set_conditions(old.conditions)
        return model
