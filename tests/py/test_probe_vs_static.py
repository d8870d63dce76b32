"""The dynamic stress probe converges to the exact static stiffness, and the affine part of the
static solve equals the micromechanical stiffness of Eq. 35 with zeta = 1."""
import os

import numpy as np
import pytest

from conftest import REPO
from trueaniso import dem, engines, fabric, specimen_file, statics, triaxial


def voigt(sig):
    sym = 0.5 * (sig + sig.T)
    return np.array([sym[0, 0], sym[1, 1], sym[2, 2], sym[1, 2], sym[0, 2], sym[0, 1]])


@pytest.fixture(scope="module")
def held():
    """A 300-sphere specimen and the six stresses it holds (its shear stresses are within the
    preparation's 100 Pa of zero; the probes hold them where they are, as the static solve takes
    the state as it is). The specimen is a committed file (tests/data, prepare_spheres(300, seed=6)
    by the baseline build), not prepared here: a preparation is chaotic, and a build for
    x86-64-v3 ends in another packing, on which the x probe with rotations free is 4.4e-4 from the
    static solve (beyond this test's 2e-4) in both builds, where this packing gives 3e-6 in both:
    the tolerances below belong to a packing, not to a build."""
    scene, _ = specimen_file.load(os.path.join(REPO, "tests", "data", "spheres-300-s6.npz"))
    return scene, voigt(engines.stress(scene))


@pytest.mark.parametrize("rotations", [True, False])
def test_dynamic_probe_converges_to_static(held, rotations):
    scene, hold = held
    st = statics.static_stiffness(scene, rotations=rotations)
    tight = dict(ramp_steps=2000, gain=0.01, settle_steps=200, relative_tolerance=1e-4, unbalanced=1e-7,
                 restrain_rotations=not rotations)
    for axis in range(3):
        up = triaxial.probe(scene, hold, axis, **tight)
        down = triaxial.probe(scene, hold, axis, sign=-1, **tight)
        mean = 0.5 * (up["E"] + down["E"])
        # 0.5 % is required at the tightest setting; the +/- mean removes the secant error of
        # the finite increment, what is left is equilibrium error (~1e-5, docs/speed-vs-error.md).
        assert up["E"] == pytest.approx(st["E"][axis], rel=5e-3)
        assert mean == pytest.approx(st["E"][axis], rel=2e-4)
        for j in range(3):
            if j != axis:
                name = "nu_%s%s" % ("xyz"[axis], "xyz"[j])
                # Poisson's ratios of ~0.12: 0.5 % of that is 6e-4 absolute; the
                # +/- mean measured within 3e-4 of the static value
                assert 0.5 * (up[name] + down[name]) == pytest.approx(st["nu"][axis, j], abs=6e-4)


@pytest.mark.parametrize("rotations", [True, False])
def test_shear_probes_converge_to_static_shear_moduli(held, rotations):
    """Dynamic shear probes on gamma_yz, gamma_xz, gamma_xy against the static solve on a random
    packing, within 2e-4 with the +/- mean (as for the normal moduli; one probe alone within
    5e-3, its second-order part). Two probes, two static answers:
     - the five other strains held at zero (hold_other_strains): d tau / d gamma is C_44, C_55, C_66;
     - the five other stresses held (the paper's probe): 1/S_44, 1/S_55, 1/S_66 of S = C^-1.
    The two differ by the packing's couplings between components: with rotations free 2.2e-3 for
    G_yz on this packing, ten times the tolerance, so there a probe that measured the one would
    fail against the other (asserted); with rotations blocked only 3e-5. Measured: every mean
    within 3e-6 of its static value."""
    scene, hold = held
    st = statics.static_stiffness(scene, rotations=rotations)
    C = np.asarray(st["C"])
    tight = dict(ramp_steps=2000, gain=0.01, settle_steps=200, relative_tolerance=1e-4, unbalanced=1e-7,
                 restrain_rotations=not rotations)
    apart = 0.0
    for k, axis in enumerate(("yz", "xz", "xy")):
        for strains, static in ((True, C[3 + k, 3 + k]), (False, st["G"][k])):
            up = triaxial.probe(scene, hold, axis, hold_other_strains=strains, **tight)
            down = triaxial.probe(scene, hold, axis, sign=-1, hold_other_strains=strains, **tight)
            mean = 0.5 * (up["G"] + down["G"])
            print("G_%s other strains held %s: up %.7g down %.7g mean %.7g static %.7g (rel %.2e)"
                  % (axis, strains, up["G"], down["G"], mean, static, mean / static - 1))
            assert up["G"] == pytest.approx(static, rel=5e-3)
            assert mean == pytest.approx(static, rel=2e-4)
            assert up["gamma"] >= 1e-6 and up["axis"] == axis
            if strains:  # the other strains stayed at zero: below 1e-3 of the probed one
                assert np.abs(np.delete(up["d_strain"], 3 + k)).max() < 1e-3 * abs(up["d_strain"][3 + k])
        apart = max(apart, abs(C[3 + k, 3 + k] * np.linalg.inv(C)[3 + k, 3 + k] - 1))
    print("largest |C_kk S_kk - 1|: %.2e" % apart)
    if rotations:
        assert apart > 5 * 2e-4


def test_affine_static_equals_micromechanics_at_zeta_1(held):
    scene, _ = held
    st = statics.static_stiffness(scene, rotations=False)
    pred = fabric.prediction(scene, zeta=1.0, density="count")
    C = np.asarray(pred["voigt"])  # Appendix A, from B and M of Eqs. 33-34
    affine = np.asarray(st["affine_normal"]) + np.asarray(st["affine_shear"])  # Eq. 32, no prestress terms
    # Normal 3x3 block (the part Eqs. 40-42 use): two independent assemblies of the same sum.
    # (The shear block differs by the factor ~2 of Appendix A's C44-C66: docs/statics.md, "Eq. (32) and Appendix A".)
    np.testing.assert_allclose(C[:3, :3], affine[:3, :3], rtol=1e-10, atol=1e-10 * np.abs(affine).max())


def test_shear_block_conventions_are_the_documented_ones(held):
    """The shear block, checked against a brute-force sum instead of left out: with the
    unsymmetrised T_ijkl = (1/V) sum L_i K_jl L_k (K = k_n n n + k_s (I - n n)), the static
    affine part takes the minor-symmetrised (T_ijij + T_jiji + T_ijji + T_jiij)/4 of the
    engineering shear strain, Appendix A (A7-A9) takes (T_ijij + T_jiji)/2 (docs/statics.md
    "Eq. (32) and Appendix A"): the ~1.965x between them is that convention, nothing else. The study CSV's
    mic_G_* columns carry Appendix A's."""
    scene = held[0].copy()
    dem.refresh(scene)  # both computations and the brute force read the same contact state
    st = statics.static_stiffness(scene, rotations=False)
    C = np.asarray(fabric.prediction(scene, zeta=1.0, density="count")["voigt"])
    A = np.asarray(st["affine_normal"]) + np.asarray(st["affine_shear"])
    c = scene.contact_arrays()
    on = c["normal_force"] > 0
    L, n, kn = c["branch"][on], c["normal"][on], c["kn"][on]
    ks = kn * 2 * (1 - scene.poisson) / (2 - scene.poisson)  # Eq. (6) / Eq. (5)
    nn = n[:, :, None] * n[:, None, :]
    K = kn[:, None, None] * nn + ks[:, None, None] * (np.eye(3) - nn)
    T = np.einsum("ci,cjl,ck->ijkl", L, K, L) / scene.volume
    for a, (i, j) in enumerate([(1, 2), (0, 2), (0, 1)]):  # Voigt 4, 5, 6: yz, xz, xy
        minor = 0.25 * (T[i, j, i, j] + T[j, i, j, i] + T[i, j, j, i] + T[j, i, i, j])
        appendix = 0.5 * (T[i, j, i, j] + T[j, i, j, i])
        assert A[3 + a, 3 + a] == pytest.approx(minor, rel=1e-10)
        assert C[3 + a, 3 + a] == pytest.approx(appendix, rel=1e-10)
        assert 1.9 < C[3 + a, 3 + a] / A[3 + a, 3 + a] < 2.0  # below 2 by the cross terms
    for i in range(3):
        for k in range(3):
            assert C[i, k] == pytest.approx(T[i, i, k, k], rel=1e-10)
