"""FEBio's distortion-dependent bond relaxation (``FEBondRelaxationExpDistortion``) and how its
reactive viscoelastic weighs type II generations with it (``FEReactiveViscoelastic.cpp``
``BreakingBondMassFraction``, called with F set to generation k's Uv[k] for both of its terms),
against values computed by hand (FEBio's ma28)."""

import math

import numpy as np
import pytest

from tissuesim.materials.reactive import generations as gen
from tissuesim.materials.reactive.relaxation import Relaxation

MA28 = {"model": "relaxation-exp-distortion", "tau0": 0.2, "tau1": 0.3, "alpha": 2.0}
A = 0.5 / math.sqrt(2.0)  # ln U = (A, -A, 0) + ln s: K2 = |dev ln U| = A sqrt(2) = 0.5


def _u(s: float, a: float) -> np.ndarray:
    return s * np.diag([math.exp(a), math.exp(-a), 1.0])


def test_exp_distortion_is_febios_formula():
    """K2 = |dev h|, h = ln U (FEBio's LeftHencky of F = Uv, symmetric), so a dilatation
    (s = 1.3) adds nothing: K2 = 0.5, tau = 0.2 + 0.3 * 0.5^2 = 0.275, g(0.11) = e^-0.4
    = 0.670320046; K2 = 0 (a pure dilatation): tau = tau0, g(0.11) = e^-0.55 = 0.576949810."""
    g = Relaxation("test", MA28)
    K2 = gen.dev_log_norm(np.array([_u(1.3, A), _u(1.0, A), _u(1.1, 0.0)]))
    assert K2 == pytest.approx([0.5, 0.5, 0.0], abs=1e-15)
    got = g(np.full(3, 0.11), K2)
    assert got == pytest.approx([0.6703200460356393, 0.6703200460356393, 0.5769498103804866],
                                rel=1e-14)  # fmt: skip
    assert g(np.zeros(1), np.array([0.5])) == pytest.approx([1.0])


@pytest.mark.parametrize("kinetics", [1, 2])
def test_type_two_weights_take_each_generations_own_distortion(kinetics):
    """Generation 0 from v0 = 0.1 at U0 = 1.1 I (K2 0, tau 0.2), generation 1 from v1 = 0.3
    at K2 1 = 0.5 (tau 0.275), weighed at t = 0.5. Type II: w0 = g(0.4; 0) = e^-2 =
    0.135335283, w1 = g(0.2; 0.5) - g(0.4; 0.5) = e^(-0.2/0.275) - e^(-0.4/0.275) =
    0.483225081 - 0.233506479 = 0.249718602 (not g(0.4; 0) for the second term: 0.347889798),
    the reforming bonds 1 - g(0.2; K2) at their own K2 (0.5 here: 0.516774919; 0 for a K2 of
    0: 1 - e^-1). Type I (masses f0 = 1, f1 = 0.7): w_k = f_k g(t - v_k; K2_k) and the
    reforming bonds 1 - sum w_k."""
    g = Relaxation("test", MA28)
    s = gen.new_state(1, 3)
    gen.push(s, np.array([0]), _u(1.1, 0.0)[None], 0.1, np.array([1.0]))
    gen.push(s, np.array([0]), _u(1.0, A)[None], 0.3, np.array([0.7]))
    w, fr = gen.weights(s, g, kinetics, 0.5)
    g04, g02 = math.exp(-2.0), math.exp(-0.2 / 0.275)
    if kinetics == 1:
        assert w[0] == pytest.approx([g04, 0.7 * g02], rel=1e-13)
        assert fr[0] == pytest.approx(1.0 - g04 - 0.7 * g02, rel=1e-13)
        return
    assert w[0] == pytest.approx([g04, 0.24971860209891206], rel=1e-13)
    assert fr[0] == pytest.approx(0.5167749188101746, rel=1e-13)
    _, fr0 = gen.weights(s, g, kinetics, 0.5, k2_new=np.zeros(1))
    assert fr0[0] == pytest.approx(1.0 - math.exp(-1.0), rel=1e-13)
    # before any generation the bonds are whole
    assert gen.weights(gen.new_state(1, 3), g, kinetics, 0.5)[1] == pytest.approx([1.0])
