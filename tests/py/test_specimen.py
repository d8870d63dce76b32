"""Sphere specimens: the consolidated state, the exact size distribution after the similarity
rescale, file round trip, reproducibility, and the paper's e and Zm at N = 4000."""
import hashlib
import os
import subprocess
import sys

import numpy as np
import pytest

from trueaniso import dem, engines, psd, specimen, specimen_file

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def small():
    scene, log = specimen.prepare_spheres(150, seed=4)
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
    pos, radii, scale, side = specimen.random_loose_packing(150, psd.PAPER_SPHERES, 4)
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
    specimen_file.save(str(path), scene, seed=4, parameters=log)
    loaded, meta = specimen_file.load(str(path))
    assert meta["seed"] == 4 and meta["format_version"] == 4
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


@pytest.mark.long
def test_paper_void_ratio_and_coordination_at_4000():
    """The paper's sphere specimen: e = 0.584 and Zm in 5.94-5.99, within 2 % at N >= 4000. Long
    (minutes on one core): the full-size preparation is what is checked, no smaller one stands in."""
    scene, _ = specimen.prepare_spheres(4000, seed=1)
    st = specimen.state(scene)
    assert st["void_ratio"] == pytest.approx(0.584, rel=0.02)
    assert st["Zm"] == pytest.approx(5.965, rel=0.02)
    # Finite-size shear stress shrinks as ~1/sqrt(N): 0.96 % of p measured at 4000 spheres.
    sig = engines.stress(scene)
    assert np.abs(sig - np.diag(np.diag(sig))).max() < 0.02 * 100e3
