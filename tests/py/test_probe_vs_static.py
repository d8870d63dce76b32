"""The dynamic stress probe converges to the exact static stiffness (issue 5), and the affine part
of the static solve equals the micromechanical stiffness of Eq. 35 with zeta = 1 (issue 4 x 5)."""
import numpy as np
import pytest

from trueaniso import engines, fabric, specimen, statics, triaxial


@pytest.fixture(scope="module")
def held():
    scene, _ = specimen.prepare_spheres(300, seed=6)
    return scene, np.diag(engines.stress(scene)).copy()


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
        # The issue asks 0.5 % at the tightest setting; the +/- mean removes the secant error of
        # the finite increment, what is left is equilibrium error (~1e-5, docs/speed-vs-error.md).
        assert up["E"] == pytest.approx(st["E"][axis], rel=5e-3)
        assert mean == pytest.approx(st["E"][axis], rel=2e-4)
        for j in range(3):
            if j != axis:
                name = "nu_%s%s" % ("xyz"[axis], "xyz"[j])
                assert 0.5 * (up[name] + down[name]) == pytest.approx(st["nu"][axis, j], abs=1e-3)


def test_affine_static_equals_micromechanics_at_zeta_1(held):
    scene, _ = held
    st = statics.static_stiffness(scene, rotations=False)
    pred = fabric.prediction(scene, zeta=1.0, density="count")
    C = np.asarray(pred["voigt"])  # Appendix A, from B and M of Eqs. 33-34
    affine = np.asarray(st["affine_normal"]) + np.asarray(st["affine_shear"])  # Eq. 32, no prestress terms
    # Normal 3x3 block (the part Eqs. 40-42 use): two independent assemblies of the same sum.
    # (The shear block differs by the factor ~2 of Appendix A's C44-C66: docs/statics.md section 5.)
    np.testing.assert_allclose(C[:3, :3], affine[:3, :3], rtol=1e-10, atol=1e-10 * np.abs(affine).max())
