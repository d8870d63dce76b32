"""The rotation factor calibrated on the contrast a_i^2 (trueaniso.zeta; docs/statics.md,
"Rotation factor calibrated on the contrast"): Eq. (25), recovery of known zeta_h, zeta_v from
data generated with them on a real micro-structure, invariance to Nc/V against the magnitude
definition, and refusal of input that cannot be fitted."""
import os
import subprocess
import sys

import numpy as np
import pytest

from trueaniso import dem, fabric, specimen_file, statics, zeta

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# Stretches of the branch vectors (L -> D L, normals kept) that turn the isotropic specimen's
# B and M into anisotropic micro-structures: B -> D B D, M_ijkl -> D_i D_k M_ijkl.
STRETCHES = ((1.0, 1.0, 1.0), (1.1, 1.0, 0.9), (0.9, 1.05, 1.1), (1.0, 0.9, 1.15))


@pytest.fixture(scope="module")
def scene(specimen_300):
    s, _ = specimen_file.load(str(specimen_300))
    dem.refresh(s)  # contacts of the final positions, the state the static solve linearises
    return s


def stretched(f, d):
    d = np.asarray(d)
    return dict(f, B=np.asarray(f["B"]) * np.outer(d, d), M=np.einsum("ijkl,i,k->ijkl", np.asarray(f["M"]), d, d))


@pytest.fixture(scope="module")
def states(scene):
    """(A_n, A_s) per stretched state, Nc/V of Eq. (36) and counted."""
    f = fabric.fabric(scene)
    out = {}
    for density in ("eq36", "count"):
        p = [zeta.parts_from_fabric(stretched(f, d), scene.shear_modulus, scene.poisson, density) for d in STRETCHES]
        out[density] = tuple(np.array([q[k] for q in p]) for k in (0, 1))
    return out


def test_eq25_by_hand():
    # E = (100, 200, 400): a_x^2 = 100^(1/3) / (200 * 400)^(1/6) = 2^(-1/2), a_y^2 = 1, a_z^2 = 2^(1/2).
    assert zeta.a_squared([100.0, 200.0, 400.0]) == pytest.approx([2 ** -0.5, 1.0, 2 ** 0.5], rel=1e-14)
    assert zeta.a_squared([3.0, 3.0, 3.0]) == pytest.approx([1.0, 1.0, 1.0], rel=1e-15)


def test_eq25_product_is_one_and_scale_free():
    E = np.random.default_rng(1).uniform(100e6, 500e6, size=(20, 3))
    a = zeta.a_squared(E)
    assert np.prod(a, axis=1) == pytest.approx(np.ones(20), rel=1e-14)
    assert zeta.a_squared(3.7 * E) == pytest.approx(a, rel=1e-14)


def test_one_zeta_is_eq37(scene):
    # The directional C reduces to Eq. (37) (engines/theory/Micromechanics) when zeta_h = zeta_v.
    A_n, A_s = zeta.parts_from_scene(scene, "eq36")
    for z in (0.0, 0.552, 1.0):
        assert zeta.young_moduli(A_n, A_s, z, z) == pytest.approx(fabric.prediction(scene, z, "eq36")["E"], rel=1e-12)


def test_fit_recovers_known_zetas(states):
    A_n, A_s = states["eq36"]
    E = 0.8 * zeta.young_moduli(A_n, A_s, 0.3, 0.7)  # any common factor: only the contrast is fitted
    fit = zeta.fit_contrast(E, A_n, A_s)
    assert fit["zeta_h"] == pytest.approx(0.3, abs=1e-6)
    assert fit["zeta_v"] == pytest.approx(0.7, abs=1e-6)
    assert fit["rms"] < 1e-9
    assert fit["rms_at_1"] > 1e3 * fit["rms"] and fit["rms_at_paper"] > 1e3 * fit["rms"]
    assert np.prod(fit["a_fit"], axis=1) == pytest.approx(np.ones(len(E)), rel=1e-12)
    common = zeta.fit_common(zeta.young_moduli(A_n, A_s, 0.45, 0.45), A_n, A_s)
    assert common["zeta"] == pytest.approx(0.45, abs=1e-6)


def test_contrast_zeta_ignores_nc_v_magnitude_zeta_does_not(states):
    A_n, A_s = states["eq36"]
    E = zeta.young_moduli(A_n, A_s, 0.5, 0.5)
    eq36 = zeta.fit_contrast(E, *states["eq36"])
    count = zeta.fit_contrast(E, *states["count"])
    scaled = zeta.fit_contrast(1.3 * E, *states["eq36"])
    for other in (count, scaled):
        assert other["zeta_h"] == pytest.approx(eq36["zeta_h"], abs=1e-8)
        assert other["zeta_v"] == pytest.approx(eq36["zeta_v"], abs=1e-8)
    # The magnitude root moves with the Nc/V choice (Eq. 36 is 2% above the count here) ...
    m36 = zeta.magnitude_zeta(A_n[1], A_s[1], E[1])
    mcount = zeta.magnitude_zeta(states["count"][0][1], states["count"][1][1], E[1])
    assert m36["zeta_h"] == pytest.approx(0.5, abs=1e-9)
    assert mcount["zeta_h"] > m36["zeta_h"] + 0.02
    # ... and with any common factor of the E_i.
    assert zeta.magnitude_zeta(A_n[1], A_s[1], 1.3 * E[1])["zeta_v"] > 0.5 + 0.2


def test_magnitude_zeta_is_rotation_factor(scene):
    free = statics.static_stiffness(scene, rotations=True)
    ref = statics.rotation_factor(scene, free=free, blocked=statics.static_stiffness(scene, rotations=False))
    got = zeta.magnitude_zeta(*zeta.parts_from_scene(scene, "count"), free["E"])
    assert got["zeta_h"] == pytest.approx(ref["zeta_h"], abs=1e-9)
    assert got["zeta_v"] == pytest.approx(ref["zeta_v"], abs=1e-9)


def test_refuses_what_it_cannot_fit(states):
    A_n, A_s = states["eq36"]
    E = zeta.young_moduli(A_n, A_s, 0.3, 0.7)
    with pytest.raises(ValueError, match="at least 2 states"):
        zeta.fit_contrast(E[:1], A_n[:1], A_s[:1])
    bad = E.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        zeta.fit_contrast(bad, A_n, A_s)
    bad[2, 1] = -1.0
    with pytest.raises(ValueError, match="positive"):
        zeta.fit_contrast(bad, A_n, A_s)
    with pytest.raises(ValueError, match="one A_n and one A_s per state"):
        zeta.fit_contrast(E, A_n[:3], A_s[:3])
    # Isotropic everything: a_i^2 = 1 whatever zeta, nothing to fit.
    iso = np.tile(np.eye(3), (3, 1, 1))
    with pytest.raises(ValueError, match="does not depend"):
        zeta.fit_contrast(np.full((3, 3), 2e8), iso, 0.5 * iso)


def script(*args):
    return subprocess.run([sys.executable, os.path.join(REPO, "bench", "bench_zeta.py"), *args],
                          capture_output=True, text=True, timeout=120)


def test_script_bad_input_one_line(tmp_path):
    cases = [(), ("--csv", str(tmp_path / "missing.csv"))]
    thin = tmp_path / "thin.csv"
    thin.write_text("state,probe,E\n1,x,3e8\n")
    cases.append(("--csv", str(thin)))
    for args in cases:
        p = script(*args)
        assert p.returncode == 2, p.stderr
        assert p.stderr.count("\n") == 1 and p.stderr.startswith("error: "), p.stderr
