"""Size distribution: the paper's D50 and Cu, closed form and sampled."""
import numpy as np
import pytest

from trueaniso import psd


def test_linear_gradation_has_paper_d50_and_cu():
    d = psd.SizeDistribution.from_d50_cu(0.195e-3, 1.25)
    # closed form: dmin = D50/(1 + r/2), r = (Cu-1)/(0.6-0.1 Cu) = 0.25/0.475
    r = 0.25 / 0.475
    assert d.d[0] == pytest.approx(0.195e-3 / (1 + r / 2), rel=1e-12)
    assert d.d50 == pytest.approx(0.195e-3, rel=1e-12)
    assert d.cu == pytest.approx(1.25, rel=1e-12)


@pytest.mark.parametrize("n", [100, 4000])
def test_sample_follows_mass_distribution(n):
    dist = psd.PAPER_SPHERES
    diam = dist.sample(n, np.random.default_rng(3))
    assert diam.min() >= dist.d[0] * (1 - 1e-12) and diam.max() <= dist.d[-1] * (1 + 1e-12)
    d50, cu = psd.mass_d50_cu(diam)
    # stratified sampling: the finite sample's D50/Cu deviate by O(1/n); 1% at n = 100
    tol = 1e-2 if n < 1000 else 1e-3
    assert d50 == pytest.approx(0.195e-3, rel=tol)
    assert cu == pytest.approx(1.25, rel=tol)


def test_sampling_is_reproducible():
    a = psd.PAPER_SPHERES.sample(500, np.random.default_rng(9))
    b = psd.PAPER_SPHERES.sample(500, np.random.default_rng(9))
    assert np.array_equal(a, b)


@pytest.mark.parametrize("args", [([1e-4], [0.0, 1.0]), ([2e-4, 1e-4], [0, 1]), ([1e-4, 2e-4], [0, 0.9]),
                                  ([-1e-4, 2e-4], [0, 1])])
def test_bad_tables_are_refused(args):
    with pytest.raises(ValueError):
        psd.SizeDistribution(*args)


def test_bad_d50_cu_are_refused():
    with pytest.raises(ValueError):
        psd.SizeDistribution.from_d50_cu(-1.0, 1.25)
    with pytest.raises(ValueError):
        psd.SizeDistribution.from_d50_cu(1e-4, 1.0)
