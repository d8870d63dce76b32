"""Sphere specimens: the consolidated state, the exact size distribution after the similarity
rescale, file round trip, reproducibility (within a build, and against the bits and numbers this
build's recipe is documented with), and the paper's e and Zm at N = 4000."""
import hashlib
import os
import subprocess
import sys

import numpy as np
import pytest

from trueaniso import buildarch, dem, engines, psd, specimen, specimen_file, triaxial

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def small():
    # One engine thread: the packing test_recipe_keeps_its_committed_bits compares is that of one.
    threads = engines.threads()
    engines.set_threads(1)
    try:
        scene, log = specimen.prepare_spheres(150, seed=5)
    finally:
        engines.set_threads(threads)
    return scene, log


def test_consolidated_state(small):
    scene, log = small
    st = specimen.state(scene)
    for k in ("sigma_x", "sigma_y", "sigma_z"):
        assert st[k] == pytest.approx(100e3, abs=log["stress_tolerance"])
    assert st["unbalanced"] < log["unbalanced"]
    assert st["friction"] == 0.5
    # The orthorhombic cell servoes normal stresses only; the shear stresses left are the
    # packing's finite-size fluctuation. At 150 spheres, seeds 1-6 on 1 and 2 threads leave
    # 2.8-10.3 % of p, so the bound is 15 %; the N = 4000 test below holds it to 2 %.
    sig = engines.stress(scene)
    assert np.abs(sig - np.diag(np.diag(sig))).max() < 0.15 * 100e3


def test_similarity_rescale_restores_exact_radii(small):
    scene, _ = small
    pos, radii, scale, side = specimen.random_loose_packing(150, psd.PAPER_SPHERES, 5)
    # Same seed, same sampled radii: the expansion grew them, the rescale brought them back (the
    # bodies are renumbered along the Morton curve after placement, so compared as sets).
    np.testing.assert_allclose(np.sort(scene.radii), np.sort(radii), rtol=1e-12)


def test_rescale_keeps_stress():
    scene, _ = specimen.prepare_spheres(120, seed=5, unbalanced=1e-2)
    chain = dem.Chain(scene)
    chain.run(1)
    before = engines.stress(scene)
    scene.rescale(1.37)
    chain.run(1)
    # Hertz stresses are scale free; what changes is one step of motion at unbalanced ~1e-2.
    np.testing.assert_allclose(engines.stress(scene), before, rtol=1e-3, atol=1.0)


def test_file_round_trip(small, tmp_path):
    scene, log = small
    path = tmp_path / "s.npz"
    specimen_file.save(str(path), scene, seed=5, parameters=log)
    loaded, meta = specimen_file.load(str(path))
    assert meta["seed"] == 5 and meta["format_version"] == 4
    for name in ("positions", "radii", "masses", "cell", "cell_ref", "velocity_gradient", "velocities"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(scene, name))
    # The contact history comes back: evaluating forces without motion gives the same stress.
    for s in (scene, loaded):
        s.velocities = np.zeros((s.num_bodies, 3))
        s.angular_velocities = np.zeros((s.num_bodies, 3))
        sim = engines.Simulation(s)
        sim.add(engines.ContactDetection())
        sim.add(engines.ContactForces())
        sim.run(1)
    np.testing.assert_allclose(engines.stress(loaded), engines.stress(scene), rtol=1e-12, atol=1e-9)


def _prepare_in_subprocess(tmp_path, name):
    out = tmp_path / name
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, os.path.join(REPO, "pyscripts", "prepare_specimen.py"), "--n", "120",
                           "--seed", "8", "--unbalanced", "1e-2", "--quiet", "--out", str(out)],
                          env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    # The mechanical state only: the file's own checksum also covers its metadata, which holds the
    # creation time and the wall time of the preparation.
    with np.load(out) as z:
        return hashlib.sha256(b"".join(z[k].tobytes() for k in sorted(z.files) if k != "meta")).hexdigest()


def test_same_seed_one_thread_is_bit_identical(tmp_path):
    assert _prepare_in_subprocess(tmp_path, "a.npz") == _prepare_in_subprocess(tmp_path, "b.npz")


def test_recipe_keeps_its_committed_bits(small):
    """The default recipe on 150 spheres, seed 5, one thread, makes tests/data/spheres-150-s5.npz to
    the last bit (e 0.6069, Zm 5.874; 110,000 steps of expansion, 4,000 of unloading to 20 kPa, 6,000
    of consolidation). The preparation is chaotic: a change of the last bit anywhere in its steps (a
    sum's order, a time step rule, a default) ends in another packing, and every documented specimen
    (docs/specimens.md) then stops reproducing. A change meant to move the packing regenerates the
    file (tests/data/README.md) and the documented numbers with it; one not meant to fails here."""
    if engines.build_arch() != buildarch.BASELINE:  # this process runs another level: the baseline's, apart
        from test_processor_bits import _baseline_build as has_baseline, assert_same_bits, remade
        has_baseline()
        assert_same_bits(remade("spheres", (150, 5), {}), "spheres-150-s5.npz")
        return
    scene, log = small
    committed, meta = specimen_file.load(os.path.join(REPO, "tests", "data", "spheres-150-s5.npz"))
    for name in ("positions", "radii", "cell", "orientations"):
        np.testing.assert_array_equal(getattr(scene, name), getattr(committed, name), err_msg=name)
    steps = ("steps_expansion", "steps_unloading", "steps_consolidation")
    assert tuple(log[k] for k in steps) == (110000, 4000, 6000)
    assert tuple(meta["parameters"][k] for k in steps) == (110000, 4000, 6000)
    st = specimen.state(scene)
    assert (round(st["void_ratio"], 4), round(st["Zm"], 3)) == (0.6069, 5.874)


def test_the_default_specimen_keeps_its_contacts_to_state_21(small, tmp_path):
    """The paper's Zm stays within 5.94-5.99 over its 39 states (Fig. 8a). A specimen consolidated at
    friction 0.5 from the unloaded packing keeps its contacts; one whose friction is switched to 0.5
    at 100 kPa (the variant grown-to-target, the earlier default) loses them at large |q|. State 21
    (b = 0.5, sigma_z 140 kPa), reached straight from the specimen, measured on 150 spheres: Zm falls
    by 0.014 (seed 5, this one), 0.014 and 0.068 (seeds 6, 7) with the default recipe (unloaded to
    20 kPa), by 0.350, 0.192 and 0.315 with grown-to-target; at 1000 spheres (seed 1) by 0.037
    against 0.367. A bound of 0.1 lies between, and e stays put (1e-4: the packing does not creep;
    measured 1.3e-5 to 1.9e-5)."""
    scene, log = small
    path = str(tmp_path / "s.npz")
    specimen_file.save(path, scene, seed=5, parameters=log)
    copy, _ = specimen_file.load(path)  # the fixture's scene stays as prepared for the other tests
    before = engines.coordination(copy)["Zm"], engines.void_ratio(copy)
    triaxial.reach_state(copy, 0.5, 140e3)
    after = engines.coordination(copy)["Zm"], engines.void_ratio(copy)
    assert before[0] - after[0] < 0.1, (before, after)
    assert abs(after[1] - before[1]) < 1e-4


@pytest.mark.long
def test_documented_1000_sphere_specimen(tmp_path):
    """The command docs/specimens.md gives for the 1000-sphere specimen, seed 1, one thread, under the
    time step rule it was made with (smallest-inertia, the default before per-axis), by the
    baseline's module, makes the e, Zm and step counts it gives (at the digits it gives them). Long
    (2-3 min on one core)."""
    from test_processor_bits import _baseline_build as has_baseline
    has_baseline()
    out = tmp_path / "s.npz"
    proc = subprocess.run([sys.executable, os.path.join(REPO, "pyscripts", "prepare_specimen.py"), "--n", "1000",
                           "--seed", "1", "--threads", "1", "--checkpoint-every", "0", "--time-step", "smallest-inertia",
                           "--quiet", "--out", str(out)],
                          env=dict(os.environ, OMP_NUM_THREADS="1", TRUEANISO_LEVEL=buildarch.BASELINE),
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stderr
    _, meta = specimen_file.load(str(out))
    st, p = meta["summary"], meta["parameters"]
    assert (round(st["void_ratio"], 4), round(st["Zm"], 3)) == (0.5808, 5.962)
    assert (p["steps_expansion"], p["steps_unloading"], p["steps_consolidation"]) == (120000, 22000, 4000)


@pytest.mark.long
def test_paper_void_ratio_and_coordination_at_4000():
    """The paper's sphere specimen: e = 0.584 and Zm in 5.94-5.99; the recipe is held to e within 0.01
    and Zm in 5.92-6.00 at 4000 spheres (the recipe's seed scatter at 1000 spheres is about 0.003 in e and
    0.02 in Zm, docs/studies/specimens.md "Seeds"). Long (minutes on one core): the full-size preparation is
    what is checked, no smaller one stands in."""
    scene, _ = specimen.prepare_spheres(4000, seed=1)
    st = specimen.state(scene)
    assert abs(st["void_ratio"] - 0.584) <= 0.01
    assert 5.92 <= st["Zm"] <= 6.00
    # Finite-size shear stress shrinks as ~1/sqrt(N): 0.96 % of p measured at 4000 spheres.
    sig = engines.stress(scene)
    assert np.abs(sig - np.diag(np.diag(sig))).max() < 0.02 * 100e3
