"""The generations of FEBio's reactive visco-elasticity against a transcription of FEBio's
own list algorithm (``FEReactiveViscoelastic.cpp``: NewGeneration, ReformingBondMassFraction,
CullGenerations with wmin > 0, StressWeakBonds), the trigger's gate on the reforming bonds, a
damaged strong bond (FEBio's ma67 set-up), and its checkpoint."""

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.materials.reactive.damage import ElasticDamage
from tissuesim.materials.reactive.reactive_viscoelastic import ReactiveViscoelastic
from tissuesim.materials.reactive.relaxation import Relaxation

EXP = {"model": "exponential", "tau": 0.15}


def neo(E=1e3, nu=0.3):
    return ts.NeoHookean(youngs_modulus=E, poisson_ratio=nu)


def sqrtm(C):
    w, v = np.linalg.eigh(C)
    return v @ np.diag(np.sqrt(w)) @ v.T


class FebioLists:
    """FEBio's per-point lists, transcribed: Uv, Jv, v, f (type I), the Cauchy stress."""

    def __init__(self, bond, relaxation, emin, wmin):
        self.bond, self.g, self.emin, self.wmin = bond, relaxation, emin, wmin
        self.Uv, self.v, self.f, self.nmax = [], [], [], 0

    def _w(self, ig, t):
        K2 = ts_dev_log(self.Uv[ig])
        return self.f[ig] * self.g(np.array([t - self.v[ig]]), np.array([K2]))[0]

    def reforming(self, t):
        return 1.0 - sum(self._w(ig, t) for ig in range(len(self.v) - 1))

    def update(self, F, t):
        Ui = np.linalg.inv(self.Uv[-1]) if self.Uv else np.eye(3)
        Fu = F @ Ui
        E = 0.5 * (Fu.T @ Fu - np.eye(3))
        fr = 1.0 - sum(self._w(ig, t) for ig in range(len(self.v)))
        if not (np.linalg.norm(E) > max(self.emin, 2.2e-15) and fr >= self.wmin):
            return
        self.Uv.append(sqrtm(F.T @ F))
        self.v.append(t)
        self.f.append(self.reforming(t))
        ng = len(self.v)
        self.nmax = max(self.nmax, ng)
        if ng >= 3 and ng >= self.nmax:
            w0, w1 = self._w(0, t), self._w(1, t)
            if w0 < self.wmin:
                self.v[1] = (w0 * self.v[0] + w1 * self.v[1]) / (w0 + w1)
                self.Uv[1] = (self.Uv[0] * w0 + self.Uv[1] * w1) / (w0 + w1)
                self.f[1] = (w0 * self.f[0] + w1 * self.f[1]) / (w0 + w1)
                for lst in (self.Uv, self.v, self.f):
                    lst.pop(0)
        self.f[-1] = self.reforming(t)  # the next iterate's update at the same time

    def cauchy(self, F, t):
        if not self.v:
            return cauchy(self.bond, F)
        s = np.zeros((3, 3))
        for ig in range(len(self.v)):
            w = self._w(ig, t)
            if ig == 0:
                s += w * cauchy(self.bond, F)
            else:
                U = self.Uv[ig - 1]
                s += w * cauchy(self.bond, F @ np.linalg.inv(U)) / np.linalg.det(U)
        return s


def ts_dev_log(U):
    h = np.log(np.linalg.eigvalsh(U))
    return np.linalg.norm(h - h.mean())


def cauchy(law, F):
    return law.stress(F[None])[0] @ F.T / np.linalg.det(F)


@pytest.mark.parametrize("wmin", [0.0, 0.2])
def test_generations_and_culling_are_febios_lists(wmin):
    """A wandering deformation over 14 steps (loading, a hold, unloading): after every step
    the weak bonds' Cauchy stress is FEBio's, culling included (wmin = 0.2 merges)."""
    rng = np.random.default_rng(5)
    bond = neo(500.0, 0.2)
    relax = {"model": "exp_distortion", "tau0": 0.1, "tau1": 1.0, "alpha": 1.0}
    law = ReactiveViscoelastic(ts.NeoHookean(shear_modulus=1e-9, lame_lambda=0.0), bond=bond,
                               relaxation=relax, emin=1e-3, wmin=wmin).bind(1, 3)  # fmt: skip
    ref = FebioLists(bond, Relaxation("t", relax), 1e-3, wmin)
    F, t, h, merged = np.eye(3), 0.0, 0.05, False
    for n in range(14):
        if n not in (5, 6, 7):  # 5..7 held
            F = F + 0.04 * rng.standard_normal((3, 3))
        t += h
        law.begin_step(h)
        law.accept_step(F[None])
        ref.update(F, t)
        got = cauchy(law, F)
        assert law.generations[0] == len(ref.v)
        np.testing.assert_allclose(got - cauchy(law.elastic, F), ref.cauchy(F, t),
                                   rtol=1e-10, atol=1e-9)  # fmt: skip
        merged |= len(ref.v) < n + 1 - 3
    assert merged == (wmin > 0.0)


def test_reforming_bonds_count_past_the_trigger_only():
    law = ReactiveViscoelastic(neo(), bond=neo(), relaxation=EXP, emin=1e-3).bind(1, 3)
    F = np.diag([1.1, 1.0, 1.0])[None]
    law.begin_step(0.1)
    law.accept_step(F)
    law.begin_step(0.1)
    w, fr = law.weights()
    assert fr[0] == pytest.approx(1.0 - w[0, 0]) and fr[0] > 0.4
    breaking = law.stress(F) - neo().stress(F)
    small, large = F * 1.0003, F * 1.003  # strains from U_r about 3e-4 and 3e-3
    np.testing.assert_allclose(law.stress(small) - neo().stress(small),
                               w[0, 0] * neo().stress(small), rtol=1e-12)  # fmt: skip
    Ur_inv = np.linalg.inv(F[0])
    reform = fr[0] * neo().stress(large @ Ur_inv) @ Ur_inv
    np.testing.assert_allclose(law.stress(large) - neo().stress(large),
                               w[0, 0] * neo().stress(large) + reform, rtol=1e-12)  # fmt: skip
    assert np.allclose(breaking, w[0, 0] * neo().stress(F))


def test_a_damaged_strong_bond_scales_the_weak_bonds():
    """FEBio's ma67: the strong bonds an elastic damage, the weak ones times its 1 - D."""
    damage = ElasticDamage(neo(), damage={"model": "weibull", "alpha": 2.5, "mu": 125.0},
                           criterion="von_mises_stress")  # fmt: skip
    law = ReactiveViscoelastic(damage, bond=neo(2e3), relaxation=EXP, wmin=1e-3).bind(2, 3)
    F = np.repeat(np.diag([1.15, 0.97, 0.97])[None], 2, axis=0)
    law.begin_step(0.1)
    law.accept_step(F)
    D = law.elastic.damage
    assert np.all((D > 0.05) & (D < 0.95))
    law.begin_step(0.1)
    G = F * 1.01
    w, fr = law.weights()
    Ur_inv = np.linalg.inv(F)
    weak = w[:, :1, None] * neo(2e3).stress(G) + fr[:, None, None] * (
        neo(2e3).stress(G @ Ur_inv) @ Ur_inv)  # fmt: skip
    expect = (1 - D)[:, None, None] * (neo().stress(G) + weak)
    np.testing.assert_allclose(law.stress(G), expect, rtol=1e-12)
    state = law.state_arrays()
    assert "base_xmax" in state and np.all(state["base_xmax"] > 100.0)
    other = ReactiveViscoelastic(damage, bond=neo(2e3), relaxation=EXP, wmin=1e-3).bind(2, 3)
    other.set_state_arrays(state)
    other.begin_step(0.1)
    np.testing.assert_array_equal(other.stress(G), law.stress(G))
