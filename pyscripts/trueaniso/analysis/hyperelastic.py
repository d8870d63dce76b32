r"""Orthotropic hyperelastic model of the paper, section 4.1 (Eqs. 21-25).

$E_i = 9KG/(3K+G)\,a_i^4$ (21), $\nu_{ij} = (3K-2G)/(2(3K+G))\,a_i^2/a_j^2$ (22), $G_{ij} = G a_i^2 a_j^2$ (23),
with $\det(a) = 1$, so $a_i^2 = E_i^{1/3}/(E_j E_k)^{1/6}$ (25). The scalar part
$E_0 = 9KG/(3K+G)$ and $\nu_0 = (3K-2G)/(2(3K+G))$ are an isotropic Young modulus and Poisson ratio,
hence $K = E_0/(3(1-2\nu_0))$ and $G = E_0/(2(1+\nu_0))$.
"""
import numpy as np

__all__ = ["fabric_a2", "scalar_moduli", "predicted", "quadratic_fit", "states_from_rows"]


def fabric_a2(E):
    """Eq. (25): $a_i^2 = E_i^{1/3}/(E_j E_k)^{1/6}$ from the three directional Young's moduli.

    Args:
        E: ($E_x$, $E_y$, $E_z$), or a stack (..., 3); all > 0.

    Raises:
        ValueError: a modulus <= 0.

    Example:
        >>> from trueaniso.analysis import hyperelastic
        >>> [round(a, 4) for a in hyperelastic.fabric_a2([300e6, 300e6, 360e6])]
        [0.9701, 0.9701, 1.0627]
    """
    E = np.asarray(E, dtype=float)
    if np.any(E <= 0):
        raise ValueError("Young moduli must be > 0")
    out = np.empty_like(E)
    for i in range(3):
        j, k = [m for m in range(3) if m != i]
        out[..., i] = E[..., i] ** (1 / 3) / (E[..., j] * E[..., k]) ** (1 / 6)
    return out


def scalar_moduli(E, nu):
    r"""K and G of the hyperelastic model from a state's $E_i$ and $\nu_{ij}$ (Eqs. 21-22 inverted).

    $E_0$ is the mean of $E_i/a_i^4$ (all equal when Eq. 21 holds), $\nu_0$ the mean of the six
    $\nu_{ij} a_j^2/a_i^2$ (Eq. 22); $K = E_0/(3(1 - 2\nu_0))$, $G = E_0/(2(1 + \nu_0))$.

    Args:
        E: ($E_x$, $E_y$, $E_z$), Pa.
        nu: 3x3, nu[i, j] = $\nu_{ij}$ (i loading, j lateral); the diagonal is ignored.

    Returns:
        dict: ``K``, ``G``, ``E0``, ``nu0`` and ``a2`` (Eq. 25).

    Raises:
        ValueError: nu0 outside (-1, 0.5).

    Example:
        Moduli the model gives for K = 140 MPa, G = 143 MPa give them back:

        >>> from trueaniso.analysis import hyperelastic
        >>> E, nu, G = hyperelastic.predicted(140e6, 143e6, [0.97, 0.97, 1 / 0.97 ** 2])
        >>> m = hyperelastic.scalar_moduli(E, nu)
        >>> print("K = %.1f MPa, G = %.1f MPa" % (m["K"] / 1e6, m["G"] / 1e6))
        K = 140.0 MPa, G = 143.0 MPa
    """
    E = np.asarray(E, dtype=float)
    nu = np.asarray(nu, dtype=float)
    a2 = fabric_a2(E)
    E0 = float(np.mean(E / a2 ** 2))
    vals = [nu[i, j] * a2[j] / a2[i] for i in range(3) for j in range(3) if i != j]
    nu0 = float(np.mean(vals))
    if not -1 < nu0 < 0.5:
        raise ValueError("the Poisson ratios give nu0 = %.3f outside (-1, 0.5)" % nu0)
    return dict(K=E0 / (3 * (1 - 2 * nu0)), G=E0 / (2 * (1 + nu0)), E0=E0, nu0=nu0, a2=a2)


def predicted(K, G, a2):
    r"""Eqs. (21)-(23) forward: the orthotropic moduli of K, G and the fabric's $a_i^2$.

    Args:
        K: bulk modulus, Pa.
        G: shear modulus, Pa.
        a2: ($a_x^2$, $a_y^2$, $a_z^2$), whose product is 1.

    Returns:
        (E, nu, G_ij): E (3,), nu (3x3, nu[i, j] = $\nu_{ij}$, NaN on the diagonal), $G_{ij}$ ($G_{yz}$, $G_{xz}$,
        $G_{xy}$).

    Example:
        >>> from trueaniso.analysis import hyperelastic
        >>> E, nu, G = hyperelastic.predicted(140e6, 143e6, [1.0, 1.0, 1.0])
        >>> print("E = %.1f MPa, nu = %.4f, G = %.1f MPa" % (E[0] / 1e6, nu[0, 1], G[0] / 1e6))
        E = 320.0 MPa, nu = 0.1190, G = 143.0 MPa
    """
    a2 = np.asarray(a2, dtype=float)
    E0 = 9 * K * G / (3 * K + G)
    nu0 = (3 * K - 2 * G) / (2 * (3 * K + G))
    E = E0 * a2 ** 2
    nu = nu0 * a2[:, None] / a2[None, :]
    np.fill_diagonal(nu, np.nan)
    Gij = G * np.array([a2[1] * a2[2], a2[0] * a2[2], a2[0] * a2[1]])
    return E, nu, Gij


def quadratic_fittable(x):
    """A quadratic in Zm needs three distinct Zm: states of one contact network share Zm exactly
    (a short cross-anisotropic path of 300 spheres gave two such of three), and a fit through two
    abscissae is any parabola through two points (numpy warns, $R^2$ means nothing)."""
    return len(np.unique(np.asarray(x, float))) >= 3


def quadratic_fit(x, y):
    """K or G against Zm as a quadratic, $c_1 Z_m^2 + c_2 Z_m + c_3$ (section 4.1, Table 2).

    Args:
        x: Zm of each state (at least three distinct values).
        y: K or G of each state.

    Returns:
        (c, r2): the coefficients (c1, c2, c3) and the fit's $R^2$.

    Raises:
        ValueError: fewer than three distinct Zm.

    Example:
        >>> from trueaniso.analysis import hyperelastic
        >>> c, r2 = hyperelastic.quadratic_fit([5.0, 5.5, 6.0, 6.5], [80e6, 110e6, 140e6, 170e6])
        >>> print("dK/dZm = %.0f MPa at Zm = 6, R^2 = %.3f" % ((2 * c[0] * 6 + c[1]) / 1e6, r2))
        dK/dZm = 60 MPa at Zm = 6, R^2 = 1.000
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    if not quadratic_fittable(x):
        raise ValueError("a quadratic fit against Zm needs 3 distinct Zm, not %d" % len(np.unique(x)))
    c = np.polyfit(x, y, 2)
    r2 = 1 - np.sum((np.polyval(c, x) - y) ** 2) / np.sum((y - y.mean()) ** 2)
    return c, float(r2)


def states_from_rows(rows):
    """A probe table's rows grouped by state, the shear probes left out.

    Args:
        rows: rows of probes.csv (`results.read_probes`).

    Returns:
        dict: by state id, dict(``E`` (3,), ``nu`` (3x3, NaN where not probed), ``Zm``, ``sigma``
        (3,), ``b``, ``q``).

    Example:
        >>> from trueaniso.analysis import results, hyperelastic
        >>> states = hyperelastic.states_from_rows(results.read_probes("docs/data/spheres-53004-s1"))
        >>> m = hyperelastic.scalar_moduli(states["1"]["E"], states["1"]["nu"])
        >>> print("%d states; at state 1: K = %.0f MPa, G = %.0f MPa" % (len(states), m["K"] / 1e6, m["G"] / 1e6))
        39 states; at state 1: K = 140 MPa, G = 147 MPa
    """
    out = {}
    ax = "xyz"
    for r in rows:
        if r["probe"] not in ("x", "y", "z"):  # a shear probe (yz, xz, xy: G_ij) has no E_i or nu_ij
            continue
        st = out.setdefault(r["state"], dict(E=np.full(3, np.nan), nu=np.full((3, 3), np.nan), Zm=float(r["Zm"]),
                                             sigma=np.array([float(r["sigma_x"]), float(r["sigma_y"]), float(r["sigma_z"])]),
                                             b=float(r["b"]), q=float(r["q"])))
        i = ax.index(r["probe"])
        st["E"][i] = float(r["E"])
        for name, val in ((r["nu_1_name"], r["nu_1"]), (r["nu_2_name"], r["nu_2"])):
            st["nu"][ax.index(name[3]), ax.index(name[4])] = float(val)
    return out
