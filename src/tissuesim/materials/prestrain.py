"""FEBio's ``prestrain elastic`` (``FEPrestrainElastic``): an elastic law evaluated at F Fp, Fp a
prestrain gradient that the reference configuration already carries, so that the body is
stressed at rest. FEBio's two gradients (``FEConstPrestrainGradient``,
``FEInSituStretchGradient``):

    gradient           Fp = (1 - ramp) I + ramp F0
    in_situ_stretch    Fp = lam a a + li (I - a a),  li = 1/sqrt(lam) (isochoric) or 1,
                       a the elastic law's fibre

FEBio takes the elastic law's Cauchy stress at F Fp; per unit reference volume that is

    W = W_e(F Fp) / Jp      P = P_e(F Fp) Fp^T / Jp      dP_ij/dF_kl = A_e,imkn Fp_jm Fp_ln / Jp

``F0`` is one 3 x 3 tensor or one per element ((m, 3, 3)), ``stretch`` one number or one per
element; ``bind`` expands them (and the elastic law's directions) to the integration points.
FEBio's prestrain constraint, which updates Fp until the body comes back to its reference shape,
is not this law. 3D only.
"""

from __future__ import annotations

import copy

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.validate import short

__all__ = ["PrestrainElastic"]


class PrestrainElastic(Material):
    """FEBio's ``prestrain elastic``: ``elastic`` (a material) at F Fp.

    ``PrestrainElastic(elastic=NeoHookean(youngs_modulus=1.0, poisson_ratio=0.3),
    prestrain="gradient", F0=[[1.1, 0, 0], [0, 1, 0], [0, 0, 1]])``"""

    name = "prestrain_elastic"

    def __init__(
        self,
        *,
        elastic: Material | None = None,
        prestrain: str = "gradient",
        F0: object = None,
        ramp: float = 1.0,
        stretch: object = 1.0,
        isochoric: bool = True,
    ) -> None:
        law = self.name
        if not isinstance(elastic, Material):
            raise MaterialError(f"{law}: elastic must be a material, not {short(elastic)}")
        if hasattr(elastic, "begin_step"):
            raise MaterialError(f"{law}: elastic ({elastic.name}) keeps a history; a prestrain "
                                "takes an elastic law")  # fmt: skip
        if prestrain not in ("gradient", "in_situ_stretch"):
            raise MaterialError(f"{law}: prestrain {short(prestrain)} is not 'gradient' or "
                                "'in_situ_stretch'")  # fmt: skip
        self.elastic, self.prestrain = elastic, prestrain
        self.ramp, self.isochoric = float(ramp), bool(isochoric)
        if prestrain == "gradient":
            F0 = np.eye(3) if F0 is None else np.array(F0, dtype=float)
            if F0.shape[-2:] != (3, 3) or F0.ndim not in (2, 3) or not np.isfinite(F0).all():
                raise MaterialError(f"{law}: F0 must be a 3 x 3 tensor or one per element, got "
                                    f"shape {F0.shape}")  # fmt: skip
            self.F0 = F0
            Fp = (1.0 - self.ramp) * np.eye(3) + self.ramp * F0
            if not (np.linalg.det(Fp) > 0.0).all():
                raise MaterialError(f"{law}: the prestrain gradient must have det > 0")
            self.stretch = np.array(1.0)
        else:
            if F0 is not None:
                raise MaterialError(f"{law}: an in_situ_stretch takes stretch, not F0")
            self.stretch = np.array(stretch, dtype=float)
            if self.stretch.ndim > 1 or not (self.stretch > 0.0).all():
                raise MaterialError(f"{law}: stretch must be > 0, one or one per element")
            if getattr(elastic, "fibres", None) is None or elastic.fibres.shape[1] != 1:
                raise MaterialError(
                    f"{law}: an in_situ_stretch takes its direction from the elastic law's "
                    f"fibre; {elastic.name} has none (or several)"
                )
            self.F0 = None
        self.mu, self.lam = elastic.mu, elastic.lam

    def __repr__(self) -> str:
        return f"{type(self).__name__}(elastic={self.elastic!r}, prestrain={self.prestrain!r})"

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> PrestrainElastic:
        """This law with per-element prestrains and directions expanded to the points."""
        out = copy.copy(self)
        if hasattr(self.elastic, "bind"):
            out.elastic = self.elastic.bind(n_points, dim, n_cells)
        for key, rank in (("F0", 3), ("stretch", 1)):
            value = getattr(self, key)
            if value is None or value.ndim < rank:
                continue
            m = value.shape[0]
            if m in (1, n_points):
                continue
            if (n_cells is not None and m != n_cells) or n_points % m:
                raise MaterialError(f"{self.name}: {m} values of {key} given, read as one per "
                                    f"element, but the body has {n_cells} elements")  # fmt: skip
            setattr(out, key, np.repeat(value, n_points // m, axis=0))
        return out

    def gradient(self, q: int) -> np.ndarray:
        """Fp, (q, 3, 3) or (1, 3, 3)."""
        if self.prestrain == "gradient":
            F0 = self.F0 if self.F0.ndim == 3 else self.F0[None]
            return (1.0 - self.ramp) * np.eye(3) + self.ramp * F0
        a = np.broadcast_to(self.elastic.fibres[:, 0, :], (q, 3))
        A = np.einsum("qi,qj->qij", a, a)
        lam = np.broadcast_to(self.stretch, (q,))[:, None, None]
        li = 1.0 / np.sqrt(lam) if self.isochoric else np.ones_like(lam)
        return lam * A + li * (np.eye(3) - A)

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q = F.shape[0]
        if F.shape[-1] != 3:
            raise MaterialError(f"{self.name} is 3D only")
        Fp = np.broadcast_to(self.gradient(q), (q, 3, 3))
        Jp = np.linalg.det(Fp)
        res = self.elastic.evaluate(F @ Fp, order)
        psi = res.energy / Jp
        if order == 0:
            return MaterialResponse(psi)
        P = res.stress @ np.swapaxes(Fp, 1, 2) / Jp[:, None, None]
        if order == 1:
            return MaterialResponse(psi, P)
        A = np.einsum("qimkn,qjm,qln->qijkl", res.tangent, Fp, Fp, optimize=True)
        return MaterialResponse(psi, P, A / Jp[:, None, None, None, None])
