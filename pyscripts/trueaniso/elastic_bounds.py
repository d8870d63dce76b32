r"""Physical bounds on the moduli of a packing of Hertz-Mindlin particles, for checking files.

A file that fits its schema can still hold numbers no packing of its material has: a column scaled
by 1e6, E and gamma swapped, a record's E_blocked of 1e30 Pa. These bounds are what every reader
of moduli (probe tables, statics records) checks them against before using them.

The scale is the simple cubic packing's Young's modulus at the mean stress $p$,
$E_{sc} = (12 E^{*2} p)^{1/3}/2$ with $E^* = E_p/(2(1 - \nu_p^2))$ (Eqs. 5-6 for its six contacts;
406.7 MPa at 100 kPa for the paper's particles, docs/triaxial.md). Every committed probe table
lies within 0.19-1.93 $E_{sc}$ (clump2 with rotations free to clump1 vertically); a packing's modulus
grows as $p^{1/3}$ with its contact stiffness and as $(\text{solid fraction} \times \text{coordination})^{2/3}$
with its contact density, which the densest packings raise by about 2 over the simple cubic one. So
MODULUS_RANGE, [0.01, 10] $E_{sc}$, keeps a factor of ten beyond the loosest and densest packings
measured, and refuses what no packing of the material reaches.

The compliance of a state (its three normal probes) is an elastic solid's: symmetric (reciprocity
$\nu_{ij}/E_i = \nu_{ji}/E_j$) within RECIPROCITY, and positive definite. RECIPROCITY is of
$\sqrt{S_{ii} S_{jj}}$: the committed tables reach 0.69 % (clump2, rotations free; spheres less), the
probe's own error (its relative tolerance 2e-3 on each modulus, the stress noise of the held
state); 2 % leaves three times that.
"""
import math

MODULUS_RANGE = (0.01, 10.0)  # of the simple cubic packing's modulus at the same mean stress
RECIPROCITY = 0.02  # |S_ij - S_ji| / sqrt(S_ii S_jj)


def simple_cubic_modulus(shear_modulus, poisson, stress):
    r"""E of the simple cubic packing of equal spheres at the stress (Pa): $(12 E^{*2} \sigma)^{1/3}/2$."""
    young = 2.0 * shear_modulus * (1.0 + poisson)
    contact = young / (2.0 * (1.0 - poisson * poisson))
    return math.cbrt(12.0 * contact * contact * stress) / 2.0


def modulus_problem(value, stress, material, name="E"):
    """Why a packing's modulus `value` (Pa) at mean stress `stress` (Pa) is not one a packing of the
    material (shear_modulus, poisson) has, or None."""
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0):
        return "%s = %r is not a positive number" % (name, value)
    if not (math.isfinite(stress) and stress > 0):
        return None  # no stress to scale with: the positive check above is all there is
    scale = simple_cubic_modulus(material["shear_modulus"], material["poisson"], stress)
    lo, hi = MODULUS_RANGE
    if lo * scale <= value <= hi * scale:
        return None
    return ("%s = %.6g Pa is %.3g times the simple cubic packing's %.4g MPa at this state's mean stress %.4g kPa "
            "(particles of G = %.4g Pa, nu = %.3g); a packing of them lies within %g-%g times it (an edited or "
            "scaled column, or another material?)" % (name, value, value / scale, scale / 1e6, stress / 1e3,
                                                      material["shear_modulus"], material["poisson"], lo, hi))


def compliance_problem(E, nu):
    r"""Why a state's normal compliance is not an elastic solid's, or None. E: {axis: $E_i$}; nu:
    {(i, j): $\nu_{ij}$} (i loaded, j lateral) for the axes x, y, z. $S_{ii} = 1/E_i$, $S_{ji} = -\nu_{ij}/E_i$."""
    axes = "xyz"
    S = [[0.0] * 3 for _ in range(3)]
    for i, a in enumerate(axes):
        S[i][i] = 1.0 / E[a]
        for j, b in enumerate(axes):
            if i != j:
                S[j][i] = -nu[(a, b)] / E[a]
    for i, j in ((0, 1), (1, 2), (0, 2)):
        scale = math.sqrt(S[i][i] * S[j][j])
        off = abs(S[i][j] - S[j][i]) / scale
        if off > RECIPROCITY:
            a, b = axes[i], axes[j]
            return ("nu_%s%s/E_%s = %.4g and nu_%s%s/E_%s = %.4g 1/GPa differ by %.2g %% of sqrt(S_%s%s S_%s%s), "
                    "beyond the %g %% reciprocity of an elastic solid (swapped or edited columns?)"
                    % (a, b, a, -S[j][i] * 1e9, b, a, b, -S[i][j] * 1e9, 100 * off, a, a, b, b, 100 * RECIPROCITY))
    sym = [[0.5 * (S[i][j] + S[j][i]) for j in range(3)] for i in range(3)]
    minors = (sym[0][0], sym[0][0] * sym[1][1] - sym[0][1] * sym[1][0], _det3(sym))
    if not all(m > 0 for m in minors):
        return ("its compliance (1/E_i on the diagonal, -nu_ij/E_i off it) is not positive definite: no elastic solid "
                "has these E_i and nu_ij (swapped or edited columns?)")
    return None


def _det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
