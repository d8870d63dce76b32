"""The default probe of a clump2 held state is reciprocal and agrees with the exact static
compliance of the state; the one-sided probe (`--probe-sides one`) is not (docs/studies/clumps.md 5j)."""
import os

import numpy as np
import pytest

from conftest import REPO, assert_page_is_its_data
from trueaniso import engines, specimen_file, statics, triaxial

STATE = os.path.join(REPO, "tests", "data", "clump2-300-s4-state4.npz")


def reciprocity(S):
    """trueaniso.analysis.seeds' measure: the largest abs(S_ij - S_ji) over their mean."""
    return max(abs(S[i, j] - S[j, i]) / (0.5 * (abs(S[i, j]) + abs(S[j, i]))) for i, j in ((0, 1), (0, 2), (1, 2)))


def probed_compliance(**kw):
    """The x, y, z probes' compliance: column i is d_eps / d_sigma_i of the probe on i."""
    P = np.zeros((3, 3))
    for i, axis in enumerate("xyz"):
        scene, meta = specimen_file.load(STATE)
        hold = triaxial.path_stresses("true-triaxial", meta["parameters"]["b"], meta["parameters"]["sigma_z"])
        r = triaxial.probe(scene, hold, axis, **kw)
        P[:, i] = np.array(r["d_strain"][:3]) / r["d_stress"][i]
    return P, r["sides"]


@pytest.fixture(scope="module")
def one_thread():
    threads = engines.threads()
    engines.set_threads(1)  # the bits of the file's tests/data/README.md measurements
    yield
    engines.set_threads(threads)


def test_default_probe_of_a_clump2_state_is_reciprocal(one_thread):
    """300 clump2 clumps held at state 4 (tests/data/README.md): with sliding suppressed the held
    state moves by itself (bodies with one contact roll on their neighbours) by ~1e-3 of a probe's
    strain over its few hundred steps, 1-2 % of the lateral strains. The default probe (two-sided
    on clumps free to rotate, its stages settled 300 steps) cancels it: measured reciprocity 0.14 %
    against the static compliance's own 0.08 %, off-diagonal compliances within 0.38 % of the static
    ones, diagonal within 0.11 %. The one-sided probe (`--probe-sides one`): 1.06 %, 0.77 %, 0.23 %. Tolerances:
    the issue's 0.5 % for the reciprocity (between the two), 0.5 % for the off-diagonal terms (above
    what the default gives, below the one-sided 0.77 %), 0.3 % for the diagonal ones. The file's
    bits and one engine thread make the probes' bits: what is measured here is what runs."""
    scene, _ = specimen_file.load(STATE)
    S = np.array(statics.static_stiffness(scene, rotations=True)["S"])[:3, :3]
    assert reciprocity(S) < 1.5e-3
    off = ~np.eye(3, dtype=bool)
    P, sides = probed_compliance()
    assert sides == 2
    assert reciprocity(P) < 5e-3
    assert np.abs(P / S - 1)[off].max() < 5e-3 and np.abs(np.diag(P / S) - 1).max() < 3e-3
    one_sided, sides = probed_compliance(sides="one")
    assert sides == 1
    assert reciprocity(one_sided) > 5e-3 and np.abs(one_sided / S - 1)[off].max() > 5e-3  # what the test tells apart


def test_the_study_s_tables_are_those_of_its_data(tmp_path):
    """docs/studies/clumps.md 5j's tables are what bench/probe_sides.py --doc writes from
    docs/data/probe-sides, and the data say what the section does: over the 39 states of each of
    the three clump2 seeds the default probe is reciprocal within 0.5 % and the one-sided probe is
    not."""
    import sys
    sys.path.insert(0, os.path.join(REPO, "bench"))
    import probe_sides
    data = os.path.join(REPO, "docs", "data", "probe-sides")
    assert_page_is_its_data(tmp_path, "studies/clumps.md", lambda doc: probe_sides.main_doc(doc, data))
    for seed in (1, 2, 3):
        records = probe_sides.read(data, "clump2-2000-s%d-all.jsonl" % seed)
        default = [r for r in records if r["variant"] == probe_sides.SIDES[-1][0]]
        one_sided = [r for r in records if r["variant"] == probe_sides.SIDES[0][0]]
        assert len(default) == len(one_sided) == 39
        assert max(r["reciprocity"] for r in default) < 5e-3 < max(r["reciprocity"] for r in one_sided)
