"""Particle size distributions given as cumulative mass fraction against diameter.

The paper gives D50 and Cu only (sphere, clump1: D50 = 0.195 mm, Cu = 1.25; clump2: 0.216 mm,
1.43). We take the simplest gradation that has both: cumulative mass linear in diameter
between d_min and d_max. Then D50 = (d_min + d_max)/2 and Cu = D60/D10 fix d_min and d_max.
Any other gradation can be given as a table (sizes, cumulative mass), as YADE's psdSizes/psdCumm.
"""
import numpy as np

__all__ = ["SizeDistribution", "mass_d50_cu"]


class SizeDistribution:
    """A particle size distribution: cumulative mass fraction against diameter, as YADE's psdSizes/psdCumm.

    Args:
        diameters: increasing diameters, m (at least two).
        cumulative_mass: the mass fraction finer than each, rising from 0 to 1.

    Raises:
        ValueError: arrays of other lengths, diameters not increasing, a cumulative mass that does
            not rise from 0 to 1.

    Example:
        The paper's spheres (D50 0.195 mm, Cu 1.25), as a linear gradation, and a sample of it:

        >>> import numpy as np
        >>> from trueaniso import psd
        >>> dist = psd.SizeDistribution.from_d50_cu(0.195e-3, 1.25)
        >>> print("D50 = %.3f mm, Cu = %.2f" % (dist.d50 * 1e3, dist.cu))
        D50 = 0.195 mm, Cu = 1.25
        >>> d = dist.sample(1000, np.random.default_rng(1))
        >>> print("sample: D50 = %.3f mm, Cu = %.2f" % tuple(x * f for x, f in zip(psd.mass_d50_cu(d), (1e3, 1))))
        sample: D50 = 0.195 mm, Cu = 1.25
    """
    def __init__(self, diameters, cumulative_mass):
        d = np.asarray(diameters, dtype=float)
        c = np.asarray(cumulative_mass, dtype=float)
        if d.ndim != 1 or d.shape != c.shape or d.size < 2:
            raise ValueError("size distribution: diameters and cumulative mass need the same length >= 2")
        if np.any(d <= 0) or np.any(np.diff(d) <= 0):
            raise ValueError("size distribution: diameters must be > 0 and increasing")
        if abs(c[0]) > 1e-12 or abs(c[-1] - 1) > 1e-12 or np.any(np.diff(c) < 0):
            raise ValueError("size distribution: cumulative mass must rise from 0 to 1")
        self.d, self.cum = d, c

    @classmethod
    def from_d50_cu(cls, d50, cu):
        """Linear mass gradation with the given D50 and Cu = D60/D10."""
        if d50 <= 0:
            raise ValueError("size distribution: D50 must be > 0")
        if not 1.0 < cu < 6.0:
            raise ValueError("size distribution: Cu must lie in (1, 6) for a linear gradation")
        # D60 = dmin + 0.6 w, D10 = dmin + 0.1 w, D60 = Cu D10  =>  w = dmin (Cu - 1)/(0.6 - 0.1 Cu)
        ratio = (cu - 1.0) / (0.6 - 0.1 * cu)
        dmin = d50 / (1.0 + 0.5 * ratio)
        return cls([dmin, dmin * (1.0 + ratio)], [0.0, 1.0])

    def diameter_at(self, mass_fraction):
        """The diameter at a cumulative mass fraction, interpolated linearly in the table."""
        return float(np.interp(mass_fraction, self.cum, self.d))

    @property
    def d50(self):
        """D50, the diameter at half the mass."""
        return self.diameter_at(0.5)

    @property
    def cu(self):
        """Cu = D60/D10, the coefficient of uniformity."""
        return self.diameter_at(0.6) / self.diameter_at(0.1)

    def sample(self, n, rng):
        """n diameters whose mass distribution follows the table.

        Within a segment of constant mass density the number density goes as $d^{-3}$; its CDF
        is inverted in closed form. Stratified uniforms (one per 1/n quantile, shuffled) keep
        small specimens close to the target D50 and Cu. Products, quotients and square roots only
        (correctly rounded on every processor): numpy's power runs another implementation on
        processors with AVX-512, and these diameters decide a packing's bits (docs/runs.md).
        """
        if n < 1:
            raise ValueError("size distribution: need at least one particle")
        seg_mass = np.diff(self.cum)
        a, b = self.d[:-1], self.d[1:]
        # number of particles per unit mass-density in each segment: integral of d^-3 / (vol)
        w = seg_mass / (b - a) * 0.5 * (1.0 / (a * a) - 1.0 / (b * b))
        w = w / w.sum()
        u = (rng.permutation(n) + rng.random(n)) / n
        seg = np.minimum(np.searchsorted(np.cumsum(w), u, side="right"), len(w) - 1)
        start = np.concatenate(([0.0], np.cumsum(w)))[seg]
        v = np.clip((u - start) / w[seg], 0.0, 1.0)
        ia, ib = 1.0 / (a[seg] * a[seg]), 1.0 / (b[seg] * b[seg])
        return 1.0 / np.sqrt(ia - v * (ia - ib))


def mass_d50_cu(diameters):
    """D50 and Cu = D60/D10 of a finite sample of diameters, by mass (for checking a specimen).

    Returns:
        (D50, Cu), D50 in the diameters' unit.

    Example:
        >>> from trueaniso import psd
        >>> d50, cu = psd.mass_d50_cu([1.0, 1.0, 2.0, 2.0])
        >>> print("D50 = %.3f, Cu = %.3f" % (d50, cu))
        D50 = 2.000, Cu = 1.875
    """
    d = np.sort(np.asarray(diameters, dtype=float))
    m = np.cumsum(d ** 3)
    cum = (m - 0.5 * d ** 3) / m[-1]
    at = lambda f: float(np.interp(f, cum, d))  # noqa: E731
    return at(0.5), at(0.6) / at(0.1)


# The paper's D50 (m) and Cu of each assembly (section 2.1).
PAPER_D50_CU = dict(sphere=(0.195e-3, 1.25), clump1=(0.195e-3, 1.25), clump2=(0.216e-3, 1.43))
PAPER_SPHERES = SizeDistribution.from_d50_cu(*PAPER_D50_CU["sphere"])
PAPER_CLUMP2 = SizeDistribution.from_d50_cu(*PAPER_D50_CU["clump2"])
