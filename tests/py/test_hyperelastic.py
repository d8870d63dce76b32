"""Orthotropic hyperelastic model (Eqs. 21-25): forward and inverse agree, det(a) = 1."""
import numpy as np
import pytest

from trueaniso.analysis import hyperelastic


def test_inverse_recovers_k_g_and_a():
    K, G = 180e6, 160e6
    a2 = np.array([0.95, 1.0, 1.0 / 0.95])  # det(a) = 1 means a_x^2 a_y^2 a_z^2 = 1
    E, nu, Gij = hyperelastic.predicted(K, G, a2)
    m = hyperelastic.scalar_moduli(E, nu)
    assert m["K"] == pytest.approx(K, rel=1e-12)
    assert m["G"] == pytest.approx(G, rel=1e-12)
    np.testing.assert_allclose(m["a2"], a2, rtol=1e-12)
    assert np.prod(m["a2"]) == pytest.approx(1.0, rel=1e-12)


def test_eq24_cross_anisotropic_relations():
    a2 = np.array([1.1, 1.1, 1 / 1.21])
    E, nu, Gij = hyperelastic.predicted(100e6, 90e6, a2)
    ratio = a2[0] / a2[2]
    assert np.sqrt(E[0] / E[2]) == pytest.approx(ratio, rel=1e-12)   # Eq. 24
    assert Gij[2] / Gij[0] == pytest.approx(ratio, rel=1e-12)        # G_hh / G_vh
    assert nu[0, 1] / nu[2, 0] == pytest.approx(ratio, rel=1e-12)    # nu_hh / nu_vh


def test_isotropic_elasticity_is_the_special_case():
    E, nu = 300e6, 0.12
    m = hyperelastic.scalar_moduli([E] * 3, np.full((3, 3), nu))
    assert m["E0"] == pytest.approx(E) and m["nu0"] == pytest.approx(nu)
    assert 9 * m["K"] * m["G"] / (3 * m["K"] + m["G"]) == pytest.approx(E, rel=1e-12)


def test_bad_moduli_refused():
    with pytest.raises(ValueError):
        hyperelastic.fabric_a2([1.0, -1.0, 1.0])
