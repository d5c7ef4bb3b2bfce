"""FEM vertices that move with a rigid body: their DOFs are held in their bodies (a support
each, so every check and elimination counts them as held) and the system maps what acts on
them onto the rigid body's six DOFs (a master-slave reduction, exact: no penalty).

A linked vertex at rest offset r from the body's centre is at x = c + R r. With p = R r and
the tangent q = (dc, dtheta) (``rigid/body.py``), dx = T dq with T = [I, -[p]x]; the second
derivative of x along dtheta, contracted with the force g on the vertex, is
G = (g p^T + p g^T) / 2 - (g . p) I (from exp([t]x) p = p + t x p + t x (t x p) / 2 + ...).

Over the whole tangent space, x = P q with P the identity on every DOF but the linked ones,
whose rows are T. The reduced Phi has gradient P^T g and Hessian P^T H P + sum G:
H restricted to the other DOFs (the linked rows and columns are eliminated as prescribed),
plus C = H[:, S] T into the rigid columns (rows outside S) and its transpose, plus
T^T H[S, S] T and G into the rigid block. The pattern gets those entries once
(``pattern_entries``); contact's extra Hessian (its own sparsity) is mapped the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.frames.rotations import skew

__all__ = ["RigidLinks"]


@dataclass(eq=False)
class RigidLinks:
    """Every linked vertex of a system: ``dofs`` (m, 3) its tangent DOFs (= configuration
    entries: FEM bodies' are the same), ``rigid`` (m,) the rigid block it follows, ``offsets``
    (m, 3) its rest offset from that block's centre, ``rigid_dofs`` (K, 6) and
    ``rigid_config`` (K, 12) where each rigid block sits in q and in c."""

    dofs: np.ndarray
    rigid: np.ndarray
    offsets: np.ndarray
    rigid_dofs: np.ndarray
    rigid_config: np.ndarray
    n: int  # the tangent size

    def __post_init__(self) -> None:
        flat = self.dofs.ravel()
        self.mask = np.zeros(self.n, dtype=bool)
        self.mask[flat] = True
        self.free_rows = ~self.mask

    # -- positions ----------------------------------------------------------------------------
    def rotations(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(centres (K, 3), rotations (K, 3, 3)) of the rigid blocks in configuration c."""
        z = c[self.rigid_config]
        return z[:, :3], z[:, 3:12].reshape(-1, 3, 3)

    def arms(self, c: np.ndarray) -> np.ndarray:
        """p = R r of every linked vertex (m, 3)."""
        _, R = self.rotations(c)
        return np.einsum("mij,mj->mi", R[self.rigid], self.offsets)

    def place(self, c: np.ndarray) -> np.ndarray:
        """c with every linked vertex at c_k + R_k r (in place, returned)."""
        centres, _ = self.rotations(c)
        c[self.dofs] = centres[self.rigid] + self.arms(c)
        return c

    # -- the map onto the rigid DOFs ----------------------------------------------------------
    def tangent_map(self, p: np.ndarray) -> sp.csr_matrix:
        """T as an (n, n) matrix: rows of the linked DOFs, columns of their rigid blocks."""
        m = len(self.rigid)
        blocks = np.zeros((m, 3, 6))
        blocks[:, :, :3] = np.eye(3)
        blocks[:, :, 3:] = -skew(p)
        rows = np.broadcast_to(self.dofs[:, :, None], (m, 3, 6))
        cols = np.broadcast_to(self.rigid_dofs[self.rigid][:, None, :], (m, 3, 6))
        return sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(self.n, self.n))

    def reduce_gradient(self, gradient: np.ndarray, p: np.ndarray) -> None:
        """Add T^T g (force and moment about the centre) to each rigid block's gradient; the
        linked DOFs keep theirs (the force the rigid body applies: their reaction)."""
        g = gradient[self.dofs]
        wrench = np.concatenate([g, np.cross(p, g)], axis=1)
        np.add.at(gradient, self.rigid_dofs[self.rigid], wrench)

    def reduced_hessian(self, H: sp.spmatrix, gradient: np.ndarray, p: np.ndarray):
        """The entries P^T H P + G adds to H (with the linked rows and columns then
        eliminated), as a COO matrix: C and C^T (C = H[:, S] T, rows outside S), T^T H T and
        the curvature G."""
        T = self.tangent_map(p)
        C = (H @ T).tocsr()
        keep = sp.diags(self.free_rows.astype(float))
        inner = (T.T @ C).tocoo()
        cross = (keep @ C).tocoo()
        g = gradient[self.dofs]
        gp = np.einsum("mi,mj->mij", g, p)
        curv = 0.5 * (gp + np.swapaxes(gp, 1, 2)) - np.einsum("mi,mi->m", g, p)[:, None, None] * (
            np.eye(3)
        )
        rot = self.rigid_dofs[self.rigid][:, 3:]
        rows = np.broadcast_to(rot[:, :, None], curv.shape).ravel()
        cols = np.broadcast_to(rot[:, None, :], curv.shape).ravel()
        return sp.coo_matrix(
            (
                np.concatenate([cross.data, cross.data, inner.data, curv.ravel()]),
                (
                    np.concatenate([cross.row, cross.col, inner.row, rows]),
                    np.concatenate([cross.col, cross.row, inner.col, cols]),
                ),
            ),
            shape=H.shape,
        )

    def pattern_entries(self, rows: np.ndarray, cols: np.ndarray) -> tuple:
        """The (rows, cols) the reduction adds to a pattern of entries (rows, cols): the
        rigid blocks, their couplings to every DOF next to a linked one, and between rigid
        blocks whose vertices share an element."""
        # random values: SciPy's product drops sums that cancel, and generic values cancel
        # nowhere, so every structural entry shows
        rng = np.random.default_rng(0)
        H = sp.csr_matrix((rng.uniform(1, 2, len(rows)), (rows, cols)), shape=(self.n, self.n))
        p = rng.uniform(1, 2, (len(self.rigid), 3))
        extra = self.reduced_hessian(H, rng.uniform(1, 2, self.n), p)
        blocks = self.rigid_dofs
        r = np.broadcast_to(blocks[:, :, None], (len(blocks), 6, 6)).ravel()
        c = np.broadcast_to(blocks[:, None, :], (len(blocks), 6, 6)).ravel()
        return np.concatenate([extra.row, r]), np.concatenate([extra.col, c])
