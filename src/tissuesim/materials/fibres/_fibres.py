"""Fibre directions and the engine of the fibre-reinforced laws: W(I1, I2, I4_1..I4_n, J).

Directions are reference unit vectors a (3 components; in 2D plane strain the in-plane part
a' = (a1, a2) and a3 enter as I4 = a' . C a' + a3^2). Given one per law (shape (3,): the same
everywhere) or one per point (shape (q, 3), q the batch of F). A law given one per element
(shape (m, 3)) is expanded to its integration points by ``bind(n_points, dim)``, which the
model calls with its points grouped per element (``points_per_cell`` consecutive points).

Invariants and their derivatives (a per point, G the gradient, H the second derivative):

    I1 = |F|^2 (+1 in 2D)     G1 = 2 F                  H1 = 2 delta_ik delta_jl
    I2 (``_hyperelastic``)    G2 = 2 (I1 F - F C)       H2 there
    I4 = a . C a              G4 = 2 (F a) (x) a        H4 = 2 delta_ik a_j a_l

Uncoupled: W = w(Ib) + U(J), Ib_a = J^(-e_a) I_a with e = 2/3 (I1, I4) and 4/3 (I2):

    W_a  = w_a s_a,  s_a = J^(-e_a)                  W_J  = -sum_a w_a e_a Ib_a / J + U'
    W_ab = w_ab s_a s_b                              W_aJ = -s_a (sum_b w_ab e_b Ib_b + e_a w_a) / J
    W_JJ = sum_ab w_ab e_a Ib_a e_b Ib_b / J^2 + sum_a w_a e_a (e_a + 1) Ib_a / J^2 + U''

Coupled: W = w(I) + U(J) with a law-given U. Then P = sum_a W_a G_a + W_J cof F and
A = sum_a W_a H_a + W_J d2J + sum_ab W_ab G_a (x) G_b (J counted as an invariant with G = cof).
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.isotropic._common import (
    IDENTITY,
    bcast,
    check_input,
    cofactor,
    det,
    det_hessian,
)
from tissuesim.materials.soft_tissue._hyperelastic import HyperelasticMaterial, inverted_error
from tissuesim.validate import short

__all__ = ["FibreLaw", "unit_vectors", "local_axes", "planar_keys"]


def planar_keys(**values: object) -> tuple[str, ...]:
    """The direction keys given with 2 components (a 2D body's in-plane form): ``bind`` refuses
    them on a 3D body, where a third component was meant and lost."""
    out = []
    for key, value in values.items():
        try:
            shape = np.shape(value)
        except ValueError:  # ragged: unit_vectors says so
            continue
        if shape[-1:] == (2,):
            out.append(key)
    return tuple(out)


def unit_vectors(law: str, key: str, value: object) -> np.ndarray:
    """(3,) or (m, 3) finite non-zero vectors, normalised; a 2-vector gets a zero third
    component."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise MaterialError(
            f"{law}: {key} must be a vector or a list of vectors, not {short(value)}"
        ) from None
    if v.ndim not in (1, 2) or v.shape[-1] not in (2, 3) or v.size == 0:
        raise MaterialError(
            f"{law}: {key} must be a vector [x, y, z] or one per element (m, 3), "
            f"got shape {v.shape}"
        )
    if v.shape[-1] == 2:
        v = np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if not np.all(np.isfinite(v)) or np.any(norm == 0.0):
        raise MaterialError(f"{law}: {key} must be finite, non-zero vectors")
    return v / norm


def local_axes(law: str, a: object, d: object) -> tuple[np.ndarray, np.ndarray]:
    """FEBio's ``mat_axis type="vector"``: e1 = a/|a|, e3 = a x d / |a x d|, e2 = e3 x e1;
    returns (e1, e2), each (3,) or (m, 3)."""
    a, d = unit_vectors(law, "mat_axis_a", a), unit_vectors(law, "mat_axis_d", d)
    if a.ndim == d.ndim == 2 and len(a) != len(d) and 1 not in (len(a), len(d)):
        raise MaterialError(
            f"{law}: mat_axis_a gives {len(a)} vectors and mat_axis_d {len(d)}: give each one "
            "per element (the same number) or one vector for the whole body"
        )
    a, d = np.broadcast_arrays(a, d)
    e3 = np.cross(a, d)
    n3 = np.linalg.norm(e3, axis=-1, keepdims=True)
    if np.any(n3 < 1e-12):
        where = ""
        if a.ndim == 2 and len(a) > 1:  # a list of the wrong length is often the cause
            at = int(np.flatnonzero(n3.ravel() < 1e-12)[0])
            where = f" (at direction {at} of the {len(a)} given, one per element)"
        raise MaterialError(f"{law}: mat_axis_a and mat_axis_d must not be parallel{where}")
    e3 = e3 / n3
    return a, np.cross(e3, a)


class FibreLaw(HyperelasticMaterial):
    """A law W(I1[, I2], I4 of each fibre family, J); subclasses give ``w`` (on the isochoric
    invariants when ``uncoupled``), ``bulk`` (U(J)) and ``directions`` (the families)."""

    uncoupled: bool = True
    uses_i2: bool = False
    #: (p, n_families, 3) reference fibre directions, p = 1 (everywhere) or one per point
    fibres: np.ndarray

    def w(self, inv: np.ndarray, order: int) -> tuple:
        """(w (q,), dw/dinv (q, n), d2w/dinv2 (q, n, n)) at the invariants inv (q, n):
        columns I1, [I2,] I4 of each family (isochoric when ``uncoupled``)."""
        raise NotImplementedError

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        """(U, U', U'') of the volumetric term at J > 0."""
        raise NotImplementedError

    #: direction keys given with 2 components (``planar_keys``), refused on a 3D body
    planar: tuple[str, ...] = ()

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> FibreLaw:
        """This law with per-element directions expanded to ``n_points`` integration points
        (each element's points consecutive); itself when the directions are global or
        already per point. ``n_cells``: the body's elements, which per-element directions
        must match."""
        p = self.fibres.shape[0]
        if dim == 3 and self.planar:
            raise MaterialError(
                f"{self.name}: {', '.join(self.planar)} has 2 components on a 3D body; give "
                "[x, y, z]"
            )
        if n_cells is not None and p not in (1, n_cells, n_points):
            raise MaterialError(
                f"{self.name}: {p} fibre directions given, read as one per element, but the "
                f"body has {n_cells} elements: give one per element or one vector for the "
                "whole body"
            )
        if p in (1, n_points):
            return self
        if n_points % p:
            raise MaterialError(
                f"{self.name}: {p} fibre directions do not match {n_points} integration points "
                "(give one per element or one for the whole body)"
            )
        bound = object.__new__(type(self))
        bound.__dict__.update(self.__dict__)
        bound.fibres = np.repeat(self.fibres, n_points // p, axis=0)
        return bound

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        if self.fibres.shape[0] not in (1, q):
            raise MaterialError(
                f"{self.name} has {self.fibres.shape[0]} fibre directions (one per element or "
                f"point) but was given {q} deformation gradients"
            )
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        lnJ = np.log(Js)
        a = np.broadcast_to(self.fibres, (q,) + self.fibres.shape[1:])  # (q, nf, 3)
        ain, a3 = a[..., :d], a[..., 2] if d == 2 else np.zeros(a.shape[:2])
        Fa = np.einsum("qij,qfj->qfi", F, ain)  # (q, nf, d)
        I4 = np.einsum("qfi,qfi->qf", Fa, Fa) + a3**2
        I1 = np.einsum("qij,qij->q", F, F) + (3.0 - d)
        cols, expo = [I1[:, None]], [2.0 / 3.0]
        if self.uses_i2:
            C = np.swapaxes(F, 1, 2) @ F
            I2 = 0.5 * (I1**2 - np.einsum("qij,qij->q", C, C) - (3.0 - d))
            cols.append(I2[:, None])
            expo.append(4.0 / 3.0)
        nf = a.shape[1]
        cols.append(I4)
        e = np.array(expo + [2.0 / 3.0] * nf)
        inv = np.concatenate(cols, axis=1)  # (q, n)
        U, dU, ddU = self.bulk(Js, lnJ)
        if self.uncoupled:
            s = Js[:, None] ** (-e)
            w, g, h = self.w(inv * s, order)
        else:
            w, g, h = self.w(inv, order)
        psi = np.where(ok, w + U, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        if self.uncoupled:
            ib = inv * s
            eib = e * ib  # e_a Ib_a
            W = g * s
            WJ = -np.einsum("qa,qa->q", g, eib) / J + dU
        else:
            W, WJ = g, dU
        G = [2.0 * F]
        if self.uses_i2:
            G.append(2.0 * (bcast(I1, 3) * F - F @ C))
        G += [2.0 * Fa[:, f, :, None] * ain[:, f, None, :] for f in range(nf)]
        Gs = np.stack(G + [cof], 1)  # (q, n + 1, d, d)
        P = np.einsum("qa,qaij->qij", np.concatenate([W, WJ[:, None]], 1), Gs)
        if order == 1:
            return MaterialResponse(psi, P)
        n = inv.shape[1]
        M = np.zeros((q, n + 1, n + 1))  # second derivatives in (invariants, J)
        if self.uncoupled:
            M[:, :n, :n] = h * s[:, :, None] * s[:, None, :]
            M[:, :n, n] = -s * (np.einsum("qab,qb->qa", h, eib) + e * g) / J[:, None]
            M[:, n, n] = (
                np.einsum("qa,qab,qb->q", eib, h, eib) + np.einsum("qa,a,qa->q", g, e + 1.0, eib)
            ) / J**2 + ddU
        else:
            M[:, :n, :n] = h
            M[:, n, n] = ddU
        M[:, n, :n] = M[:, :n, n]
        Gm = Gs.reshape(q, n + 1, d * d)
        A = (np.swapaxes(Gm, 1, 2) @ (M @ Gm)).reshape(q, d, d, d, d)
        A += bcast(2.0 * W[:, 0], 5) * IDENTITY[d] + bcast(WJ, 5) * det_hessian(F)
        if self.uses_i2:
            W2 = W[:, 1]
            I = np.eye(d)
            B = F @ np.swapaxes(F, 1, 2)
            d2I2 = (
                2.0 * bcast(I1, 5) * IDENTITY[d] + 4.0 * F[:, :, :, None, None] * F[:, None, None]
            )
            d2I2 -= 2.0 * I[None, :, None, :, None] * C[:, None, :, None, :]
            d2I2 -= 2.0 * F[:, :, None, None, :] * np.swapaxes(F, 1, 2)[:, None, :, :, None]
            d2I2 -= 2.0 * B[:, :, None, :, None] * I[None, None, :, None, :]
            A += bcast(W2, 5) * d2I2
        # H4 = 2 delta_ik a_j a_l for each family, weighted
        off = 2 if self.uses_i2 else 1
        aa = np.einsum("qf,qfj,qfl->qjl", W[:, off:], ain, ain)
        A += 2.0 * np.eye(d)[None, :, None, :, None] * aa[:, None, :, None, :]
        return MaterialResponse(psi, P, A)
