"""The volumetric part of each law, psi(F) = psi_rest(F) + U(theta(F)), for the mean-dilatation
formulation (``energies/mean_dilatation.py``).

theta is the law's measure of volume change and U its lambda term, the part that locks:

    neo_hookean          theta = J             U = lam/2 (ln theta)^2
    course_neo_hookean   theta = J             U = lam/2 r(theta)^2, r the cubic of ln
    fixed_corotated      theta = J             U = lam/2 (theta - 1)^2
    linear               theta = tr F - d      U = lam/2 theta^2        (tr eps)
    stvk                 theta = (|F|^2 - d)/2 U = lam/2 theta^2        (tr E)
    mooney_rivlin, yeoh, veronda_westmann, arruda_boyce (and their coupled_*), ogden
                         theta = J             U = k/2 (ln theta)^2     (FEBio's bulk term;
                         its pressure_model "NIKE3D"/"Abaqus (GOH)": k/4 (theta^2 - 1 - 2 ln
                         theta), "Abaqus": k/2 (theta - 1)^2)
    ogden_unconstrained  theta = J             U = cp/2 (theta - 1)^2
    holzapfel_gasser_ogden, hgo_unconstrained, trans_iso_mooney_rivlin,
    trans_iso_veronda_westmann, fung_orthotropic, fung_ortho_compressible,
    tc_nonlinear_orthotropic: their bulk term with k
                         (HGO: FEBio's default k/4 (theta^2 - 1 - 2 ln theta))
    uncoupled_holmes_mow, muscle_material  theta = J   U = its bulk term with k
    arruda_boyce_unconstrained  theta = J  U = kappa/2 (J^2 - 1 - 2 ln J) (k = 2 kappa, "goh")
    isotropic_hencky     theta = J             U = lam/2 (ln theta)^2
    holmes_mow           none (U = 0: its J terms are inside its exponential, psi_rest the law)
    fiber_exp_pow, fiber_pow_linear, fiber_exp_linear (and their _uncoupled forms): none
                         (U = 0, a fibre has no bulk term)
    continuous_fiber_distribution (and _uncoupled): none (U = 0, fibres only)
    2d_trans_iso_mooney_rivlin, mooney_rivlin_von_mises_fibers  theta = J  U = their
                         matrix's bulk term with k
    solid_mixture        the sum of its components' U, which must share theta and U's kind
    uncoupled_solid_mixture  theta = J, its own bulk term with k (pressure_model as above)

psi_rest keeps every mu term (for the uncoupled soft-tissue laws: the deviatoric energy), so its
bulk stiffness is of order mu and does not lock. Shapes:
F (q, d, d) -> theta (q,), dtheta/dF (q, d, d), d2theta/dF2 (q, d, d, d, d).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError
from tissuesim.materials.base import Material
from tissuesim.materials.isotropic._common import IDENTITY, cofactor, det, det_hessian
from tissuesim.materials.soft_tissue._hyperelastic import HyperelasticMaterial, bulk_energy

__all__ = ["VolumetricPart", "volumetric_part", "VOLUMETRIC_LAWS"]

#: law name -> (theta kind, U kind)
VOLUMETRIC_LAWS = {
    "neo_hookean": ("J", "log"),
    "course_neo_hookean": ("J", "cubic_log"),
    "fixed_corotated": ("J", "quadratic_J"),
    "linear": ("trace", "quadratic"),
    "stvk": ("green_trace", "quadratic"),
    **{
        name: ("J", "log")
        for law in ("mooney_rivlin", "yeoh", "veronda_westmann", "arruda_boyce")
        for name in (law, f"coupled_{law}")
    },
    "ogden": ("J", "log"),
    "ogden_unconstrained": ("J", "quadratic_J"),
    "holzapfel_gasser_ogden": ("J", "goh"),
    "hgo_unconstrained": ("J", "goh"),
    "trans_iso_mooney_rivlin": ("J", "log"),
    "trans_iso_veronda_westmann": ("J", "log"),
    "fung_orthotropic": ("J", "log"),
    "fung_ortho_compressible": ("J", "log"),
    "uncoupled_holmes_mow": ("J", "log"),
    "tc_nonlinear_orthotropic": ("J", "log"),
    "holmes_mow": ("J", "log"),
    "arruda_boyce_unconstrained": ("J", "goh"),
    "isotropic_hencky": ("J", "log"),
    "muscle_material": ("J", "log"),  # its bulk term with k (pressure_model as above)
    **{
        name: ("J", "log")
        for law in ("fiber_exp_pow", "fiber_pow_linear", "fiber_exp_linear")
        for name in (law, f"{law}_uncoupled")
    },
    "uncoupled_solid_mixture": ("J", "log"),
    # FEBio's continuous fibre distributions (no bulk term, k = 0) and 2D trans iso
    # Mooney-Rivlin (its matrix's k and pressure_model)
    "continuous_fiber_distribution": ("J", "log"),
    "continuous_fiber_distribution_uncoupled": ("J", "log"),
    "2d_trans_iso_mooney_rivlin": ("J", "log"),
    "mooney_rivlin_von_mises_fibers": ("J", "log"),
}


@dataclass(frozen=True)
class VolumetricPart:
    theta_kind: str
    u_kind: str
    lam: float

    def theta(self, F: np.ndarray, order: int):
        """(theta, dtheta/dF or None, d2theta/dF2 or None) up to ``order``."""
        d = F.shape[-1]
        if self.theta_kind == "J":
            cof = cofactor(F)
            t = det(F, cof)
            return t, cof if order >= 1 else None, det_hessian(F) if order >= 2 else None
        if self.theta_kind == "trace":
            t = np.trace(F, axis1=1, axis2=2) - d
            dt = np.broadcast_to(np.eye(d), F.shape) if order >= 1 else None
            return t, dt, np.zeros((F.shape[0],) + (d,) * 4) if order >= 2 else None
        t = 0.5 * (np.einsum("qij,qij->q", F, F) - d)
        ddt = np.broadcast_to(IDENTITY[d], (F.shape[0],) + (d,) * 4) if order >= 2 else None
        return t, F if order >= 1 else None, ddt

    def energy(self, theta: np.ndarray, order: int):
        """(U, U', U'') at theta (q,); U = +inf (and U', U'' nan) where the law is undefined."""
        lam = self.lam
        if self.u_kind == "log":
            ok = theta > 0.0
            ln = np.log(np.where(ok, theta, 1.0))
            U = np.where(ok, 0.5 * lam * ln**2, np.inf)
            dU = np.where(ok, lam * ln / np.where(ok, theta, 1.0), np.nan)
            ddU = np.where(ok, lam * (1.0 - ln) / np.where(ok, theta, 1.0) ** 2, np.nan)
            return U, dU, ddU
        if self.u_kind == "goh":
            ok = theta > 0.0
            safe = np.where(ok, theta, 1.0)
            U, dU, ddU = bulk_energy("goh", lam, safe, np.log(safe))
            return np.where(ok, U, np.inf), np.where(ok, dU, np.nan), np.where(ok, ddU, np.nan)
        if self.u_kind == "cubic_log":
            x = theta - 1.0
            r, dr, ddr = x - x**2 / 2.0 + x**3 / 3.0, 1.0 - x + x**2, 2.0 * x - 1.0
            return 0.5 * lam * r**2, lam * r * dr, lam * (dr**2 + r * ddr)
        x = theta - 1.0 if self.u_kind == "quadratic_J" else theta
        return 0.5 * lam * x**2, lam * x, np.full_like(theta, lam)


def volumetric_part(material: Material, what: str = "formulation") -> VolumetricPart:
    """The law's theta and U (``VOLUMETRIC_LAWS``); a solid mixture's is its components' sum,
    an uncoupled viscoelastic law's its elastic law's."""
    name = getattr(material, "name", "")
    if name == "uncoupled_viscoelastic":
        # the Prony series relaxes the deviatoric part only; the bulk term U(J) stays the
        # elastic law's (``UncoupledViscoelastic._bulk``): FEBio's three-field hex8 with it
        return volumetric_part(material.elastic, what)
    if name == "solid_mixture":
        parts = [volumetric_part(p, what) for p in material.components]
        parts = [p for p in parts if p.lam != 0.0] or parts[:1]
        kinds = {(p.theta_kind, p.u_kind) for p in parts}
        if len(kinds) > 1:
            raise InputError(
                f"{what} 'mean_dilatation': the solid mixture's components have different "
                f"volumetric terms ({', '.join(sorted(f'{t} {u}' for t, u in kinds))}); use "
                "formulation = 'displacement'"
            )
        return VolumetricPart(*kinds.pop(), float(sum(p.lam for p in parts)))
    if name not in VOLUMETRIC_LAWS:
        raise InputError(
            f"{what} 'mean_dilatation' needs a law with a known volumetric part "
            f"({', '.join(VOLUMETRIC_LAWS)}); {name or type(material).__name__!r} has none: use "
            f"formulation = 'displacement'"
        )
    theta, u = VOLUMETRIC_LAWS[name]
    if isinstance(material, HyperelasticMaterial):
        # the soft-tissue laws' bulk term: its own kind (FEBio's pressure_model) and k (cp)
        return VolumetricPart("J", material.bulk_kind, float(material.k))
    return VolumetricPart(theta, u, float(material.lam))
