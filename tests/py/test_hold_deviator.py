"""The clump preparation's deviator hold (RadiusExpansion.hold_deviator, the clump1 recipe variant
'hold-deviator'): while the radii grow, the cell strains at constant volume so that the normal
stresses stay at their mean. Off, the growth is at a fixed cell, the default recipe's to the bit."""
import os
import sys

import numpy as np
import pytest

from conftest import REPO, assert_page_is_its_data, one_line_error, run_script
from trueaniso import clump_recipes, clump_specimen, dem, engines, specimen_file

DIMERS = os.path.join(REPO, "tests", "data", "clump1-200-s4.npz")


def _loaded():
    """The 200-dimer fixture (100 kPa, balanced), forces evaluated, at its own time step."""
    scene, _ = specimen_file.load(DIMERS)
    dem.refresh(scene)
    scene.dt = dem.reference_time_step(scene, 100e3)
    return scene


def test_the_cell_rate_is_the_proportional_law_on_the_normal_deviator():
    """One application against the law computed here from the measured stress and affine stiffness:
    per axis gain x step scale x (sigma_k - p) / (K_k dt), less the mean of the three (no volume change), and
    nothing without the hold (the cell stays as it is)."""
    scene = _loaded()
    sig = np.diag(engines.stress(scene))
    K = np.asarray(engines.affine_stiffness(scene))[:3]
    grow = engines.RadiusExpansion()
    grow.gain, grow.max_growth_rate = 0.01, 1e9
    grow.apply(scene)
    assert np.all(scene.strain_rate == 0.0)  # off: the fixed cell
    assert grow.deviator == pytest.approx(np.max(np.abs(sig - sig.mean())), rel=1e-12)

    scene = _loaded()
    grow = engines.RadiusExpansion()
    grow.gain, grow.deviator_gain, grow.max_growth_rate, grow.hold_deviator = 0.002, 0.01, 1e9, True
    grow.apply(scene)
    # the gain is per reference step (scene.step_scale of them a step, as every controller's)
    raw = min(1.0, 0.01 * scene.step_scale) * (sig - sig.mean()) / (K * scene.dt)
    want = raw - raw.mean()
    # 1e-9 of the largest rate: the stress is summed over contacts in the engines' order, here as
    # read back; both are the same tensor to round-off.
    np.testing.assert_allclose(scene.strain_rate, want, rtol=0, atol=1e-9 * np.max(np.abs(want)))
    assert abs(np.sum(scene.strain_rate)) <= 1e-12 * np.max(np.abs(want))
    assert np.any(scene.strain_rate != 0.0)


def _deviator_after(hold, steps=3000):
    """The fixture given a normal deviator (the cell strained at constant volume, z shortened by
    2e-4, x and y lengthened by 1e-4), then grown towards its own mean stress for `steps`: |sigma_k - p| max over p, and p."""
    scene = _loaded()
    squeeze = dem.Chain(scene)
    scene.strain_rate = np.array([1.0, 1.0, -2.0]) * 1e-4 / (200 * scene.dt)
    squeeze.run(200)
    scene.strain_rate = np.zeros(3)
    sig = np.diag(engines.stress(scene))
    before = np.max(np.abs(sig - sig.mean())) / sig.mean()
    grow = engines.RadiusExpansion()
    grow.target_pressure, grow.gain, grow.deviator_gain, grow.hold_deviator = 100e3, 0.01, 0.01, hold
    grow.max_growth_rate = dem.strain_rate_for_inertial_number(1e-2, 0.195e-3, scene.density, 100e3)
    dem.Chain(scene, damping=0.4, controllers=[grow]).run(steps)
    sig = np.diag(engines.stress(scene))
    return before, np.max(np.abs(sig - sig.mean())) / sig.mean(), sig.mean()


def test_the_hold_takes_the_normal_deviator_away_and_the_fixed_cell_keeps_it():
    """Measured on the fixture (friction 0.5): the squeeze leaves a normal deviator of 0.295 p;
    3000 steps of growth at gain 0.01 leave 3.4e-5 p with the hold and 0.271 p without (the fixed
    cell keeps it: the growth is isotropic). Bounds about halfway in log between the two (1e-2 p
    and 0.1 p), so that a hold that did nothing, or half of one, fails."""
    before, held, p_held = _deviator_after(True)
    _, fixed, p_fixed = _deviator_after(False)
    assert before > 0.1, before
    assert held < 1e-2, (held, before)
    assert fixed > 0.1, (fixed, before)
    assert p_held == pytest.approx(100e3, rel=0.05) and p_fixed == pytest.approx(100e3, rel=0.05)


def test_the_default_is_the_fixed_cell_to_the_bit():
    """hold_deviator=None is the recipe without the option: the same arrays, and no key in the log
    (a specimen made before the option records none)."""
    def prepare(**kw):
        return clump_specimen.prepare_clumps("clump1", 60, seed=4, inertial_number=5e-2, shape="dimer-1.5",
                                             stage1_pressure=100e3, mu_prep=0.0, max_steps=200_000, **kw)
    threads = engines.threads()
    engines.set_threads(1)
    try:
        a, log_a = prepare()
        b, log_b = prepare(hold_deviator=None)
    finally:
        engines.set_threads(threads)
    for name in ("positions", "orientations", "radii", "cell", "velocities"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert "hold_deviator" not in log_a and "hold_deviator" not in log_b
    assert log_a["steps_expansion"] == log_b["steps_expansion"]


@pytest.mark.parametrize("gain", [0.0, -0.1, 1.5, float("nan")])
def test_a_deviator_gain_out_of_range_is_refused(gain):
    with pytest.raises(ValueError, match="gain must lie in"):
        clump_specimen.prepare_clumps("clump1", 60, seed=4, hold_deviator=gain)
    grow = engines.RadiusExpansion()
    grow.hold_deviator, grow.deviator_gain = True, gain
    with pytest.raises(Exception, match="deviator gain must lie in"):
        grow.apply(_loaded())


def test_the_variant_is_clump1s_and_is_refused_elsewhere(tmp_path):
    assert set(clump_recipes.variant("clump1", "hold-deviator")) == {"hold_deviator"}
    assert clump_recipes.variant("clump1", "fast-growth") == {"gain": 0.1}
    with pytest.raises(ValueError, match="clump2 has no recipe variant 'hold-deviator'"):
        clump_recipes.variant("clump2", "hold-deviator")
    out = str(tmp_path / "s.npz")
    one_line_error(run_script("prepare_specimen.py", "--assembly", "clump2", "--n", 100, "--recipe", "hold-deviator",
                              "--out", out), "--recipe", "clump2 has no recipe variant 'hold-deviator'")
    one_line_error(run_script("prepare_specimen.py", "--n", 100, "--recipe", "hold-deviator", "--out", out),
                   "--recipe", "sphere has no recipe variant 'hold-deviator'")
    assert not os.path.exists(out)


@pytest.mark.long
def test_the_committed_clump_fixture_is_made_again_to_the_bit():
    """The default growth (a fixed cell) is what made tests/data/clump1-200-s4.npz: its recipe
    (fixture_recipes.clump1_200_s4) run again gives the same arrays and step counts."""
    import fixture_recipes
    from trueaniso import buildarch, engines
    if engines.build_arch() != buildarch.BASELINE:  # this process runs another level: the baseline's, apart
        from test_processor_bits import _baseline_build, assert_same_bits, remade
        _baseline_build()
        assert_same_bits(remade("clump1_200_s4", (), {}), "clump1-200-s4.npz")
        return
    scene, log = fixture_recipes.clump1_200_s4()
    ref, meta = specimen_file.load(DIMERS)
    for name in ("positions", "orientations", "radii", "cell", "velocities"):
        np.testing.assert_array_equal(getattr(scene, name), getattr(ref, name), err_msg=name)
    assert (log["steps_expansion"], log["steps_consolidation"]) == (meta["parameters"]["steps_expansion"],
                                                                   meta["parameters"]["steps_consolidation"])


@pytest.mark.parametrize("name, keyword", [("hold-deviator", "hold_deviator"), ("fast-growth", "gain")])
def test_prepare_specimen_takes_clump1s_variants(tmp_path, name, keyword):
    """A variant whose settings are keywords of prepare_clumps, not recipe parameters: validated
    with the recipe's defaults, bound to the checkpoint by its name."""
    sys.path.insert(0, os.path.join(REPO, "pyscripts"))
    import prepare_specimen
    o = prepare_specimen.options(["--assembly", "clump1", "--n", "300", "--recipe", name,
                                  "--out", str(tmp_path / "s.npz")])
    prepare_specimen.validate(o)
    assert o.mu_prep == clump_recipes.RECIPES["clump1"]["mu_prep"]
    assert prepare_specimen.settings(o)["recipe"] == name
    assert keyword in clump_recipes.variant("clump1", name)


def test_the_clump1_preparation_table_is_that_of_its_data(tmp_path):
    """docs/studies/clumps.md's clump1 preparation table is what clump1_prep.py --doc writes from
    docs/data/clump1-prep (no number typed by hand)."""
    sys.path.insert(0, os.path.join(REPO, "bench"))
    import clump1_prep
    import _bench
    assert_page_is_its_data(tmp_path, "studies/clumps.md", lambda doc: _bench.replace_block(
        doc, "clump1-prep", clump1_prep.table(clump1_prep.rows_of(os.path.join(REPO, "docs", "data", "clump1-prep")))))
