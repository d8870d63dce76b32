"""A sphere specimen whose friction is switched below the final pressure (--switch-pressure): the
radii grow at mu_prep to the switch pressure, then the cell servo compresses the packing to the
final pressure at mu_final. The default (the switch at the final pressure) is every earlier
specimen's recipe, bit for bit."""
import shutil

import numpy as np
import pytest
from conftest import one_line_error, run_script

from trueaniso import engines, specimen, specimen_file

N, SEED = 120, 5


def _volumetric_strain(scene):
    """Compression positive: the cell's volume change since the rescale (cell_ref), the strain of the
    consolidation stage alone."""
    return 1.0 - np.linalg.det(scene.cell) / np.linalg.det(scene.cell_ref)


@pytest.fixture(scope="module")
def switched():
    return specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2, switch_pressure=5e3)


@pytest.fixture(scope="module")
def default():
    return specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2)


def test_switched_specimen_is_consolidated_at_the_final_friction(switched):
    scene, log = switched
    st = specimen.state(scene)
    for k in ("sigma_1", "sigma_2", "sigma_3"):
        assert st[k] == pytest.approx(100e3, abs=log["stress_tolerance"])
    assert st["friction"] == 0.5 and log["switch_pressure"] == 5e3
    assert st["unbalanced"] < log["unbalanced"]


def test_the_cell_compresses_from_the_switch_pressure(switched, default):
    """From 5 to 100 kPa the cell shrinks by at least the Hertz overlaps' share. Independent bound:
    a contact's overlap delta of a pair with reduced radius R* under force f is
    (3 f / (4 E* sqrt(R*)))^(2/3) (Hertz), and the mean contact force of an isotropic packing is
    f = pi d^2 p / (phi Z) (the Love-Weber stress of Z/2 contacts a sphere of volume pi d^3 / 6, branch
    d); an affine compression changes the volume by 3 delta / d. Rearrangement at friction 0.5 only
    adds to it, so the measured strain is at least half of the affine estimate's change between the
    two pressures (half: the mean force stands for a distribution, the mean of f^(2/3) is below
    f^(2/3) of the mean). The default recipe's consolidation starts at the final pressure: its
    strain is below a tenth of the switched one's."""
    scene, _ = switched
    st = specimen.state(scene)
    g, nu = scene.shear_modulus, scene.poisson
    e_star = g / (1.0 - nu)  # E / (2 (1 - nu^2)) of two identical spheres
    d = 2.0 * float(np.mean(scene.radii))
    phi = 1.0 / (1.0 + st["void_ratio"])

    def affine(p):
        f = np.pi * d ** 2 * p / (phi * st["Zm"])
        delta = (3.0 * f / (4.0 * e_star * np.sqrt(d / 4.0))) ** (2.0 / 3.0)
        return 3.0 * delta / d

    estimate = affine(100e3) - affine(5e3)
    strain = _volumetric_strain(scene)
    assert strain > 0.5 * estimate, (strain, estimate)
    assert abs(_volumetric_strain(default[0])) < 0.1 * strain


def test_the_default_is_the_switch_at_the_final_pressure(default):
    """switch_pressure = pressure is the earlier recipe: the same bits, and no key in the log (a
    specimen made before the option records none)."""
    scene, log = default
    same, same_log = specimen.prepare_spheres(N, seed=SEED, unbalanced=1e-2, switch_pressure=100e3)
    for name in ("positions", "radii", "cell", "velocities"):
        np.testing.assert_array_equal(getattr(same, name), getattr(scene, name))
    np.testing.assert_array_equal(engines.stress(same), engines.stress(scene))
    assert "switch_pressure" not in log and "switch_pressure" not in same_log


@pytest.mark.parametrize("switch", [999.0, 100e3 * (1 + 1e-12)])
def test_a_switch_pressure_out_of_range_is_refused(switch):
    with pytest.raises(ValueError, match="switch pressure"):
        specimen.prepare_spheres(N, seed=SEED, switch_pressure=switch)


def test_the_lower_bound_holds_only_for_a_switch_below_the_final_pressure():
    """A final pressure below the bound (1 kPa) is still the default recipe's to make: the bound is
    on a switch below it, not on the switch the default puts at the final pressure."""
    assert specimen.switch_pressure_problem(500.0, 100e3) is not None
    with pytest.raises(ValueError, match="switch pressure 400 Pa"):
        specimen.prepare_spheres(N, seed=SEED, pressure=500.0, switch_pressure=400.0)
    _, log = specimen.prepare_spheres(N, seed=SEED, pressure=500.0, unbalanced=1e-2, switch_pressure=500.0)
    assert "switch_pressure" not in log


@pytest.mark.parametrize("args,words", [
    (["--switch-pressure", "200e3"], ["--switch-pressure 200000 Pa", "at most the final pressure"]),
    # below it the expansion's stop is met 10 % off, or by an unjammed packing: 5 million steps, then a failure
    (["--switch-pressure", "1"], ["--switch-pressure 1 Pa", "[1000, 100000]"]),
    (["--switch-pressure", "nan"], ["--switch-pressure", "finite"]),
    (["--assembly", "clump1", "--n", "98", "--switch-pressure", "5e3"], ["--switch-pressure is for spheres"]),
])
def test_prepare_specimen_refuses_a_bad_switch_pressure(tmp_path, args, words):
    proc = run_script("prepare_specimen.py", "--out", tmp_path / "s.npz", *args, timeout=120)
    one_line_error(proc, *words)
    assert proc.stdout == "" and list(tmp_path.iterdir()) == []


def test_a_specimen_of_another_switch_is_not_kept(tmp_path, specimen_100):
    """A specimen made without the option (switched at 100 kPa) is not taken for one switched at
    5 kPa; asked with the switch at the final pressure it is kept."""
    out = tmp_path / "s.npz"
    shutil.copy(specimen_100, out)  # 100 spheres, seed 3
    one_line_error(run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--switch-pressure",
                              5e3, "--out", out), "prepared with other settings", "switch_pressure")
    kept = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--switch-pressure", 100e3,
                      "--out", out)
    assert kept.returncode == 0 and "kept existing specimen" in kept.stdout, kept.stderr


def test_the_switch_is_recorded_in_the_file(switched, tmp_path):
    scene, log = switched
    path = str(tmp_path / "s.npz")
    specimen_file.save(path, scene, seed=SEED, parameters=log)
    _, meta = specimen_file.load(path)  # the metadata schema checks the field
    assert meta["parameters"]["switch_pressure"] == 5e3
