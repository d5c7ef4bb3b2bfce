"""The mean-dilatation (condensed three-field) elastic energy: locking-free and still a minimum.

A law's lambda term U(theta) (``materials/volumetric.py``) is evaluated on a volume average of
theta over a patch g instead of at each point q:

    E(x) = sum_q w_q [psi(F_q) - U(theta_q)] + sum_g V_g U(theta_bar_g),
    theta_bar_g = (1 / V_g) sum_q C_gq theta_q,   V_g = sum_q C_gq.

This is the three-field Hu-Washizu functional with the pressure and the dilatation constant per
patch and eliminated exactly (Simo, Taylor & Pister 1985; Nagtegaal, Parks & Rice 1974), so the
step stays the minimisation of one energy of x alone. The patches:

  P2 (``points_per_cell`` > 1): each element, C_eq = w_q. theta_bar = v_e / V_e for theta = J,
     the P2/P0 element (stable: Boffi, Brezzi & Fortin 2013, sec. 8.6). Stencil: the element.
  P1: each vertex, C_ae = w_e / (d + 1) for the elements e around vertex a: the ratio of the
     vertex's current to rest lumped volume (the average nodal volume / pressure element of
     Bonet & Burton 1998, FEBio's UT4 without its stabilisation). Stencil: the vertex's patch,
     so the Hessian couples vertices two apart (about 2.5x the P1 pattern's entries in 3D).

Gradient and Hessian (p_q = sum_g C_gq U'(theta_bar_g) / w_q, b_g = sum_q C_gq B_q^T theta'_q):

    dE/dx   = sum_q w_q B_q^T [P_q + (p_q - U'(theta_q)) theta'_q]
    d2E/dx2 = sum_q w_q B_q^T [A_q - U''(theta_q) theta' (x) theta' + (p_q - U'(theta_q)) theta'']
              B_q + sum_g U''(theta_bar_g) / V_g  b_g b_g^T
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.elastic import scatter_point_hessians
from tissuesim.errors import InvertedElementError
from tissuesim.kinematics.nodal import NodalKinematics
from tissuesim.materials.base import Material
from tissuesim.materials.isotropic._common import bcast, det, outer
from tissuesim.materials.psd import project_tangent_psd
from tissuesim.materials.volumetric import VolumetricPart, volumetric_part

__all__ = ["MeanDilatationEnergy", "vertex_patch_entries"]


def vertex_patch_entries(stencil: np.ndarray, cells: np.ndarray, n_nodes: int, d: int):
    """Ragged vertex patches of a P1 mesh: each vertex's DOFs (those of its elements).

    Returns (patch_dofs (T,), offsets (n+1,), slot (m, d+1, nloc)): vertex a's DOFs are
    patch_dofs[offsets[a]:offsets[a+1]], sorted; slot[e, alpha, r] is the position in
    patch_dofs of element e's local DOF r within the patch of its vertex alpha.
    """
    m, nloc = stencil.shape
    owner = np.repeat(cells.reshape(-1), nloc)  # (m*(d+1)*nloc,) the vertex
    dofs = np.repeat(stencil[:, None, :], cells.shape[1], axis=1).reshape(-1)
    key = owner.astype(np.int64) * (n_nodes * d) + dofs
    unique, inverse = np.unique(key, return_inverse=True)
    patch_dofs = unique % (n_nodes * d)
    counts = np.bincount(unique // (n_nodes * d), minlength=n_nodes)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    return patch_dofs, offsets, inverse.reshape(m, cells.shape[1], nloc)


@dataclass(eq=False)
class MeanDilatationEnergy:
    """Same interface as ``ElasticEnergy`` (accumulate, jacobians, cell_fields, fused)."""

    kinematics: NodalKinematics
    material: Material
    stencil_id: int = 0
    volumetric: VolumetricPart = field(init=False)

    def __post_init__(self) -> None:
        K = self.kinematics
        self.volumetric = volumetric_part(self.material)
        q = K.weights.size
        if K.points_per_cell > 1:  # P2: one patch per element
            nq = K.points_per_cell
            rows = np.repeat(np.arange(q // nq), nq)
            C = sp.csr_matrix((K.weights, (rows, np.arange(q))), shape=(q // nq, q))
            self._vertex = None
        else:  # P1: one patch per vertex
            nv = K.cells.shape[1]
            rows = K.cells.reshape(-1)
            cols = np.repeat(np.arange(q), nv)
            w = np.repeat(K.weights / nv, nv)
            C = sp.csr_matrix((w, (rows, cols)), shape=(K.n_nodes, q))
            self._vertex = vertex_patch_entries(K.stencil, K.cells, K.n_nodes, K.dim)
        self.C = C
        self.CT = C.T.tocsr()
        self.volumes = np.asarray(C.sum(axis=1)).ravel()

    fused = False

    def _patch_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, vertex): every pair of entries of every vertex patch, as indices into the
        ragged patch_dofs, and the patch's vertex (P1 only)."""
        dofs, offsets, _ = self._vertex
        sizes = np.diff(offsets)
        first, second, node = [], [], []
        for size in np.unique(sizes):  # a loop over patch sizes (a few dozen), not vertices
            which = np.flatnonzero(sizes == size)
            idx = offsets[which][:, None] + np.arange(size)  # (k, size) into patch_dofs
            first.append(np.repeat(idx, size, axis=1).ravel())
            second.append(np.tile(idx, (1, size)).ravel())
            node.append(np.repeat(which, size * size))
        return tuple(np.concatenate(a) for a in (first, second, node))

    def extra_entries(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(rows, cols) the Hessian needs beyond the element stencil (P1's vertex patches)."""
        if self._vertex is None:
            return None
        i, j, _ = self._patch_pairs()
        dofs = self._vertex[0]
        return dofs[i], dofs[j]

    def set_pattern(self, pattern) -> None:
        """Precompute where the vertex patches' rank-one blocks go in ``pattern``."""
        if self._vertex is None:
            return
        dofs = self._vertex[0]
        i, j, node = self._patch_pairs()
        pos = pattern.positions(dofs[i], dofs[j])
        index = np.int32 if max(pattern.nnz, dofs.size) < 2**31 else np.int64
        self._rank_one = tuple(a.astype(index) for a in (pos, i, j, node))

    # -- evaluation -----------------------------------------------------------------------------
    def _state(self, x: np.ndarray, order: int):
        K, vol = self.kinematics, self.volumetric
        F = K.deformation_gradients(x)
        response = self.material.evaluate(F, min(order, 2))
        theta, dtheta, ddtheta = vol.theta(F, order)
        U, dU, ddU = vol.energy(theta, order)
        theta_bar = (self.C @ theta) / self.volumes
        Ub, dUb, ddUb = vol.energy(theta_bar, order)
        return F, response, theta, dtheta, ddtheta, U, dU, ddU, theta_bar, Ub, dUb, ddUb

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        K = self.kinematics
        try:
            F, resp, th, dth, ddth, U, dU, ddU, thb, Ub, dUb, ddUb = self._state(x, acc.order)
        except InvertedElementError:
            acc.add_value("elastic", np.inf)
            return
        with np.errstate(invalid="ignore"):
            value = float(K.weights @ (resp.energy - U) + self.volumes @ Ub)
        acc.add_value("elastic", value if np.isfinite(value) else np.inf)
        if acc.order == 0 or not np.isfinite(value):
            return
        p = (self.CT @ dUb) / K.weights  # per point: the patch pressure U'(theta_bar)
        c = p - dU
        stress = resp.stress + bcast(c, 3) * dth
        local = K.stress_to_gradient(stress)
        acc.gradient += np.bincount(
            K.stencil.ravel(), weights=local.ravel(), minlength=acc.pattern.n
        )
        if acc.order < 2:
            return
        A = resp.tangent - bcast(ddU, 5) * outer(dth, dth) + bcast(c, 5) * ddth
        if acc.project:
            A = project_tangent_psd(A)
        scatter_point_hessians(K, A, acc, self.stencil_id)
        b = K.stress_to_gradient(dth)  # (q, nloc): w_q B_q^T theta'_q
        D = ddUb / self.volumes
        if acc.project:
            D = np.maximum(D, 0.0)
        if self._vertex is None:  # P2: b_e = sum over the element's points
            b = K.per_cell_sum(b)
            acc.pattern.accumulate(
                acc.hessian, self.stencil_id, D[:, None, None] * b[:, :, None] * b[:, None, :]
            )
            return
        dofs, offsets, slot = self._vertex
        nv = K.cells.shape[1]
        v = np.bincount(
            slot.reshape(-1),
            weights=np.repeat(b[:, None, :] / nv, nv, axis=1).reshape(-1),
            minlength=dofs.size,
        )
        pos, i, j, node = self._rank_one
        acc.hessian += np.bincount(pos, weights=D[node] * v[i] * v[j], minlength=acc.pattern.nnz)

    def jacobians(self, x: np.ndarray) -> np.ndarray:
        return det(self.kinematics.deformation_gradients(x))

    def cauchy_correction(self, x: np.ndarray) -> np.ndarray:
        """What the patch pressure changes in the law's Cauchy stress at each point, (q, 3, 3):
        (p - U'(theta)) dtheta/dF F^T / J, embedded in 3D (for theta = J, (p - U') I, the
        out-of-plane component included in plane strain)."""
        F, _, th, dth, _, U, dU, _, thb, Ub, dUb, _ = self._state(x, 1)
        p = (self.CT @ dUb) / self.kinematics.weights
        J = det(F)
        d = F.shape[-1]
        c = (p - dU) / J
        out = np.zeros((F.shape[0], 3, 3))
        out[:, :d, :d] = bcast(c, 3) * (dth @ np.swapaxes(F, 1, 2))
        if d == 2 and self.volumetric.theta_kind == "J":
            out[:, 2, 2] = p - dU  # J of the embedded F = J of the plane part
        return out

    def point_energy_density(self, x: np.ndarray) -> np.ndarray:
        """(q,) J/m^3: the point's part plus its share of the patches' energies (so that
        sum_q w_q psi_q is the energy)."""
        _, resp, _, _, _, U, _, _, _, Ub, _, _ = self._state(x, 0)
        return resp.energy - U + (self.CT @ Ub) / self.kinematics.weights

    def cell_fields(self, x: np.ndarray) -> dict[str, np.ndarray]:
        K = self.kinematics
        J = det(K.deformation_gradients(x))
        return {
            "J": K.cell_average(J),
            "energy_density": K.cell_average(self.point_energy_density(x)),
        }
