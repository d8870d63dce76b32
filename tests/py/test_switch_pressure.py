"""The sphere recipe's friction switch: the radii grow at mu_prep to the final pressure, shrink at
mu_prep to the switch pressure (the default: specimen.SWITCH_FRACTION of it), and the cell servo
compresses the packing back to the final pressure at mu_final. The named variants: grown-to-switch
(the radii grow to the switch pressure only, no unloading) and grown-to-target (the switch at the
final pressure: every specimen before the option, bit for bit)."""

import numpy as np
import pytest
from conftest import one_line_error, run_script

from trueaniso import clump_recipes, engines, specimen, specimen_file

N, SEED = 120, 5


def _volumetric_strain(scene):
    """Compression positive: the cell's volume change since the rescale (cell_ref), the strain of the
    consolidation stage alone."""
    return 1.0 - np.linalg.det(scene.cell) / np.linalg.det(scene.cell_ref)


def _variant(name):
    return clump_recipes.variant("sphere", name)


@pytest.fixture(scope="module")
def unloaded():
    return specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2)


@pytest.fixture(scope="module")
def grown_to_switch():
    return specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2, **_variant("grown-to-switch"))


@pytest.fixture(scope="module")
def grown_to_target():
    return specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2, **_variant("grown-to-target"))


def test_the_default_is_unloaded_to_the_switch_pressure(unloaded):
    scene, log = unloaded
    st = specimen.state(scene)
    for k in ("sigma_1", "sigma_2", "sigma_3"):
        assert st[k] == pytest.approx(100e3, abs=log["stress_tolerance"])
    assert st["friction"] == 0.5 and st["unbalanced"] < log["unbalanced"]
    assert log["switch_pressure"] == specimen.default_switch_pressure(100e3) == 20e3
    assert log["unloaded_from"] == 100e3 and log["steps_unloading"] > 0


@pytest.mark.parametrize("which", ["unloaded", "grown_to_switch"])
def test_the_cell_compresses_from_the_switch_pressure(which, grown_to_target, request):
    """From the switch pressure (20 kPa unloaded, 5 kPa grown-to-switch) to 100 kPa the cell shrinks by at least the Hertz overlaps' share. Independent bound:
    a contact's overlap delta of a pair with reduced radius R* under force f is
    (3 f / (4 E* sqrt(R*)))^(2/3) (Hertz), and the mean contact force of an isotropic packing is
    f = pi d^2 p / (phi Z) (the Love-Weber stress of Z/2 contacts a sphere of volume pi d^3 / 6, branch
    d); an affine compression changes the volume by 3 delta / d. Rearrangement at friction 0.5 only
    adds to it, so the measured strain is at least half of the affine estimate's change between the
    two pressures (half: the mean force stands for a distribution, the mean of f^(2/3) is below
    f^(2/3) of the mean). grown-to-target's consolidation starts at the final pressure: its strain
    is below a tenth of the switched one's."""
    scene, log = request.getfixturevalue(which)
    st = specimen.state(scene)
    g, nu = scene.shear_modulus, scene.poisson
    e_star = g / (1.0 - nu)  # E / (2 (1 - nu^2)) of two identical spheres
    d = 2.0 * float(np.mean(scene.radii))
    phi = 1.0 / (1.0 + st["void_ratio"])

    def affine(p):
        f = np.pi * d ** 2 * p / (phi * st["Zm"])
        delta = (3.0 * f / (4.0 * e_star * np.sqrt(d / 4.0))) ** (2.0 / 3.0)
        return 3.0 * delta / d

    estimate = affine(100e3) - affine(log["switch_pressure"])
    strain = _volumetric_strain(scene)
    assert strain > 0.5 * estimate, (strain, estimate)
    assert abs(_volumetric_strain(grown_to_target[0])) < 0.1 * strain


def test_the_variants_are_the_earlier_recipes(unloaded, grown_to_switch, grown_to_target):
    """grown-to-target is the switch at the final pressure, with no key in the log (a specimen made
    before the option records none) and the same bits as switch_pressure = pressure; grown-to-switch
    records the switch pressure but no unloading (the specimen --switch-pressure 5e3 made before the
    unloading). The unloaded packing is grown as grown-to-target's, to the same step."""
    scene, log = grown_to_target
    same, same_log = specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2, switch_pressure=100e3)
    for name in ("positions", "radii", "cell", "velocities"):
        np.testing.assert_array_equal(getattr(same, name), getattr(scene, name))
    np.testing.assert_array_equal(engines.stress(same), engines.stress(scene))
    for k in ("switch_pressure", "unloaded_from", "steps_unloading"):
        assert k not in log and k not in same_log
    g = grown_to_switch[1]
    assert g["switch_pressure"] == 5e3 and "unloaded_from" not in g and "steps_unloading" not in g
    assert unloaded[1]["steps_expansion"] == log["steps_expansion"]


@pytest.mark.parametrize("switch", [999.0, 100e3 * (1 + 1e-12)])
def test_a_switch_pressure_out_of_range_is_refused(switch):
    with pytest.raises(ValueError, match="switch pressure"):
        specimen.prepare_spheres(N, seed=SEED, switch_pressure=switch)


def test_the_lower_bound_holds_only_for_a_switch_below_the_final_pressure():
    """A final pressure below the bound (1 kPa) is still the recipe's to make, switched at the final
    pressure: the default switch is never below the bound, and a final pressure at or below it
    switches there (default_switch_pressure)."""
    assert specimen.switch_pressure_problem(500.0, 100e3) is not None
    assert specimen.default_switch_pressure(500.0) == 500.0
    assert specimen.default_switch_pressure(4e3) == 1e3  # 20 % would be 800 Pa: the bound instead
    with pytest.raises(ValueError, match="switch pressure 400 Pa"):
        specimen.prepare_spheres(N, seed=SEED, pressure=500.0, switch_pressure=400.0)
    _, log = specimen.prepare_spheres(N, seed=SEED, pressure=500.0, unbalanced=1e-2)
    assert "switch_pressure" not in log


@pytest.mark.parametrize("args,words", [
    (["--switch-pressure", "200e3"], ["--switch-pressure 200000 Pa", "at most the final pressure"]),
    # below it the unloading's stop is met 10 % off, or by an unjammed packing
    (["--switch-pressure", "1"], ["--switch-pressure 1 Pa", "[1000, 100000]"]),
    (["--switch-pressure", "nan"], ["--switch-pressure", "finite"]),
    (["--assembly", "clump2", "--n", "100", "--switch-pressure", "5e3"], ["the clump2 recipe switches the friction",
                                                                          "--switch-pressure 5000"]),
    (["--recipe", "grown-to-target", "--switch-pressure", "5e3"], ["grown-to-target", "--switch-pressure 5000"]),
])
def test_prepare_specimen_refuses_a_bad_switch_pressure(tmp_path, args, words):
    proc = run_script("prepare_specimen.py", "--out", tmp_path / "s.npz", *args, timeout=120)
    one_line_error(proc, *words)
    assert proc.stdout == "" and list(tmp_path.iterdir()) == []


def test_a_specimen_of_another_recipe_is_not_kept(tmp_path, grown_to_switch, grown_to_target):
    """A specimen made by the earlier recipes (switched at 100 kPa; grown to 5 kPa only) is not taken
    for the default's; asked with its own variant it is kept."""
    for (scene, log), name in ((grown_to_target, "grown-to-target"), (grown_to_switch, "grown-to-switch")):
        out = tmp_path / ("%s.npz" % name)
        specimen_file.save(str(out), scene, seed=SEED, parameters=dict(log, threads=1, recipe=name),
                           summary=specimen.state(scene))  # as prepare_specimen.py --recipe NAME records it
        args = ("--n", N, "--seed", SEED, "--threads", 1, "--unbalanced", "1e-2", "--out", out)
        one_line_error(run_script("prepare_specimen.py", *args), "prepared with other settings")
        kept = run_script("prepare_specimen.py", *args, "--recipe", name)
        assert kept.returncode == 0 and "kept existing specimen" in kept.stdout, kept.stderr


def test_the_switch_is_recorded_in_the_file(unloaded, tmp_path):
    scene, log = unloaded
    path = str(tmp_path / "s.npz")
    specimen_file.save(path, scene, seed=SEED, parameters=log)
    _, meta = specimen_file.load(path)  # the metadata schema checks the fields
    assert meta["parameters"]["switch_pressure"] == 20e3 and meta["parameters"]["unloaded_from"] == 100e3
