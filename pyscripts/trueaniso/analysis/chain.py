r"""The paper's analysis chain (sections 3.1 and 4), from a study's probe table.

Per state: the DEM $E_i$ (three axial probes) and $\nu_{ij}$, K and G of the hyperelastic model (Eqs.
21-22 inverted, hyperelastic.scalar_moduli), the DEM $a_i^2$ (Eq. 25) and the micromechanical $a_i^2$
from the state's fabric (B, M, $N_c/V$ of the row; Eqs. 37-40 with $\zeta$ in the directional form
$\sqrt{\zeta_i \zeta_k}$, trueaniso.zeta). Over the states:

- Table 2: $K(Z_m)$ and $G(Z_m)$ as quadratics, with $R^2$ (Fig. 11);
- Fig. 13: micromechanical against DEM $a_i^2$ at zeta = 1, at the paper's 0.552 and at the value
  fitted on the contrast (trueaniso.analysis.zeta_contrast);
- Figs 14-15: $E_i$ and $\nu_{ij}$ predicted through Eqs. 21-22 from K(Zm), G(Zm) of the Table 2 fits and
  the micromechanical $a_i^2$, against the DEM values, with RMSE (nu: absolute, as the paper's
  0.003; E: relative);
- Fig. 4a: $E_i/E_j$ against $\sigma_i/\sigma_j$, the power-law exponent $m$ of $E_i/E_j = (\sigma_i/\sigma_j)^m$
  (a least-squares line through the origin in log-log, all six ordered pairs of every state).

Everything here reads numbers already in the table; nothing is simulated.
"""
import numpy as np

from . import hyperelastic, zeta_contrast
from trueaniso import zeta as _zeta

__all__ = ["state_table", "table2", "stress_ratio_exponent"]

AXES = "xyz"
PAPER_VOID_RATIO = dict(spheres=0.584, clump1=0.445, clump2=0.636)  # section 2.1, at isotropic 100 kPa
PAPER_ZETA = _zeta.PAPER_ZETA  # section 4.2, zeta_h = zeta_v = 0.552 for spheres
ZETA_BOUNDS = _zeta.ZETA_BOUNDS  # the search range of every zeta fit; a fit on a bound is not determined
# Paper values the report stands beside (Table 2 in MPa; section 4.3; Table B1 in MPa).
PAPER = dict(
    spheres=dict(K=(1902.7, -22607.0, 67289.1), G=(3386.1, -40197.0, 119436.5), nu_rmse=0.003, zeta=(0.552, 0.552),
                 B1={"isotropic": dict(pred=(456.9, 456.9, 456.9), dem=(418.7, 418.7, 418.7)),
                     "21": dict(pred=(455.4, 400.8, 489.7), dem=(415.3, 367.2, 446.5))},
                 B1_fcc=dict(pred=386.7, dem=386.1)),
    clump1=dict(K=(-10.2, 151.9, -423.7), G=(-4.7, 120.0, -429.6), nu_rmse=0.036,
                B1={"isotropic": dict(pred=(340.5, 340.5, 648.0), dem=(306.0, 306.0, 581.5)),
                    "21": dict(pred=(335.5, 287.6, 684.7), dem=(297.3, 255.4, 604.2))}),
    clump2=dict(K=(48.1, -577.4, 1841.7), G=(101.7, -1229.9, 3814.8), nu_rmse=0.004,
                B1={"isotropic": dict(pred=(490.5, 490.5, 413.1), dem=(405.1, 405.1, 346.2)),
                    "21": dict(pred=(488.5, 441.6, 442.1), dem=(399.9, 356.6, 371.2))}),
)


def state_table(rows):
    r"""A probe table's complete states as arrays over states, in file order, for the fits of the chain.

    Give the rows of one rotations setting (the ``rotations`` column). States without all three axial
    probes or all six $\nu_{ij}$ are left out (a study still running).

    Args:
        rows: rows of probes.csv (`results.read_probes`).

    Returns:
        dict: ``state`` (ids), ``Zm``, ``sigma`` (n, 3), ``E`` (n, 3), ``nu`` (n, 3, 3), ``K`` and
        ``G`` (Pa, `hyperelastic.scalar_moduli`), ``a2_dem`` (n, 3, Eq. 25).

    Example:
        >>> from trueaniso.analysis import chain, results
        >>> rows = [r for r in results.read_probes("docs/data/spheres-53004-s1") if r["rotations"] == "free"]
        >>> tab = chain.state_table(rows)
        >>> print("%d states, Zm from %.2f to %.2f" % (len(tab["state"]), min(tab["Zm"]), max(tab["Zm"])))
        39 states, Zm from 5.89 to 5.93
    """
    per_state = hyperelastic.states_from_rows(rows)
    off = ~np.eye(3, dtype=bool)
    out = dict(state=[], Zm=[], sigma=[], E=[], nu=[], K=[], G=[])
    for sid, st in per_state.items():
        if not (np.all(np.isfinite(st["E"])) and np.all(np.isfinite(st["nu"][off]))):
            continue
        m = hyperelastic.scalar_moduli(st["E"], st["nu"])
        out["state"].append(sid)
        for k, v in (("Zm", st["Zm"]), ("sigma", st["sigma"]), ("E", st["E"]), ("nu", st["nu"]), ("K", m["K"]),
                     ("G", m["G"])):
            out[k].append(v)
    res = {k: (v if k == "state" else np.array(v, dtype=float)) for k, v in out.items()}
    res["a2_dem"] = hyperelastic.fabric_a2(res["E"]) if len(res["state"]) else np.zeros((0, 3))
    return res


def table2(tab):
    """Table 2: K and G (MPa) against Zm as quadratics, $c_1 Z_m^2 + c_2 Z_m + c_3$, with $R^2$.

    Args:
        tab: a `state_table`.

    Returns:
        dict or None: ``{"K": (c1, c2, c3, R^2), "G": (...)}``; None below three states.

    Example:
        >>> from trueaniso.analysis import chain, results
        >>> tab = chain.state_table(results.read_probes("docs/data/spheres-53004-s1"))
        >>> K = chain.table2(tab)["K"]
        >>> print("K = %.2f Zm^2 %+.2f Zm %+.2f MPa, R^2 = %.3f" % K)
        K = 4255.49 Zm^2 -50179.25 Zm +148060.74 MPa, R^2 = 0.892
    """
    if len(tab["state"]) < 3:
        return None
    out = {}
    for name in ("K", "G"):
        c, r2 = hyperelastic.quadratic_fit(tab["Zm"], tab[name] / 1e6)
        out[name] = (float(c[0]), float(c[1]), float(c[2]), r2)
    return out


def rising_side(c):
    """Where the quadratic $c_1 Z_m^2 + c_2 Z_m + c_3$ rises with Zm: ("above" or "below", its vertex
    -c2 / (2 c1)). K and G grow with Zm in every assembly (the paper's Fig. 11), so a fit's data
    lie on its rising side; a value on the other side is an extrapolation."""
    vertex = -c[1] / (2.0 * c[0])
    return ("above" if c[0] > 0 else "below"), float(vertex)


def rising_range(fits):
    """The Zm interval on which every quadratic of `fits` (K, G) rises: (low, high), where the
    paper's data must lie; with the reasons, e.g. "K rises with Zm only below Zm = 7.45"."""
    low, high, why = -np.inf, np.inf, []
    for name, c in fits.items():
        side, vertex = rising_side(c)
        why.append("%s rises with Zm only %s Zm = %.2f" % (name, side, vertex))
        if side == "above":
            low = max(low, vertex)
        else:
            high = min(high, vertex)
    return float(low), float(high), why


def micromechanical_a2(parts, zeta_h, zeta_v):
    """$a_i^2$ of Eq. (25) applied to the micromechanical $E_i$ of every state (n, 3)."""
    A_n, A_s = parts
    return _zeta.predicted_a_squared(A_n, A_s, zeta_h, zeta_v)


def fit_contrast(E, A_n, A_s):
    """zeta_h, zeta_v fitted on the contrast $a_i^2$ over the states (trueaniso.zeta.fit_contrast)."""
    return _zeta.fit_contrast(E, A_n, A_s, min_states=2)


def predictions(tab, fits, a2_mic):
    r"""Figs 14-15: $E_i$ (n, 3) and $\nu_{ij}$ (n, 3, 3) from Eqs. (21)-(22) with K(Zm) and G(Zm) of the
    Table 2 fits and the given $a_i^2$; with their RMSE against the DEM values."""
    K = np.polyval(fits["K"][:3], tab["Zm"]) * 1e6
    G = np.polyval(fits["G"][:3], tab["Zm"]) * 1e6
    E = np.empty_like(tab["E"])
    nu = np.empty_like(tab["nu"])
    for k in range(len(K)):
        E[k], nu[k], _ = hyperelastic.predicted(K[k], G[k], a2_mic[k])
    off = ~np.eye(3, dtype=bool)
    nu_err = (nu - tab["nu"])[:, off]
    return dict(E=E, nu=nu, E_rel_rmse=float(np.sqrt(np.mean(((E - tab["E"]) / tab["E"]) ** 2))),
                nu_rmse=float(np.sqrt(np.mean(nu_err ** 2))))


ALL_PAIRS = tuple((i, j) for i in range(3) for j in range(3) if i != j)
HORIZONTAL_PAIRS = ((0, 1), (1, 0))                                   # E_x/E_y, Fig. 4b-c's power law
VERTICAL_PAIRS = ((2, 0), (0, 2), (2, 1), (1, 2))                     # those the paper says deviate on clumps


MIN_LOG_STRESS_RATIO = 0.01


def stress_ratio_exponent(tab, pairs=ALL_PAIRS):
    r"""Fig. 4: the exponent $m$ of $E_i/E_j = (\sigma_i/\sigma_j)^m$, the stress-induced anisotropy.

    A least-squares line through the origin in log-log over the ordered pairs (i, j) of every state:
    all six for spheres (Fig. 4a), the horizontal pair for clumps (Fig. 4b-c).

    Args:
        tab: a `state_table`.
        pairs: the ordered pairs of axes (0, 1, 2 for x, y, z).

    Returns:
        dict: ``m``, ``r2`` (of the line), ``log_sigma_ratio`` and ``log_E_ratio`` (the points).

    Example:
        >>> from trueaniso.analysis import chain, results
        >>> tab = chain.state_table(results.read_probes("docs/data/spheres-53004-s1"))
        >>> fit = chain.stress_ratio_exponent(tab)
        >>> print("m = %.3f, R^2 = %.3f" % (fit["m"], fit["r2"]))
        m = 0.245, R^2 = 0.985
    """
    x, y = [], []
    for s, E in zip(tab["sigma"], tab["E"]):
        for i, j in pairs:
            x.append(np.log(s[i] / s[j]))
            y.append(np.log(E[i] / E[j]))
    x, y = np.array(x), np.array(y)
    # Reached states hold their stresses within 100 Pa, so sigma_i/sigma_j of two equal stresses is
    # 1 +/- 2e-3: a slope over such ratios alone divides noise by noise (clump2's b = 0 states gave
    # m = 503). Below a 1 % spread there is no ratio to fit.
    if len(x) == 0 or np.abs(x).max() < MIN_LOG_STRESS_RATIO:
        return None
    m = float(np.dot(x, y) / np.dot(x, x))
    r2 = 1 - np.sum((y - m * x) ** 2) / np.sum(y ** 2)
    return dict(m=m, r2=float(r2), log_sigma_ratio=x, log_E_ratio=y)


def zm_by_sign_of_q(q, zm, reference):
    """Fig. 8's asymmetry: the lowest Zm among states with q < 0 and with q > 0, and each one's
    drop below the reference (isotropic) Zm; the paper's clumps lose contacts faster at q < 0."""
    q, zm = np.asarray(q, float), np.asarray(zm, float)
    out = {}
    for name, sel in (("negative", q < 0), ("positive", q > 0)):
        low = float(zm[sel].min()) if np.any(sel) else None
        out[name] = dict(n=int(sel.sum()), lowest=low, drop=None if low is None else float(reference - low))
    return out


def fabric_parts(path, tab, shear_modulus, poisson, rotations):
    """(A_n, A_s) per state of `tab` (same order), from the fabric columns of the probe table."""
    for src in zeta_contrast.sources(path, shear_modulus, poisson, complete_only=True):
        if src["rotations"] != rotations:
            continue
        index = {s: k for k, s in enumerate(src["states"])}
        A_n, A_s = zeta_contrast.parts_of(src)
        pick = [index[s] for s in tab["state"]]
        return A_n[pick], A_s[pick]
    return None


def zeta_per_state(tab, parts, reference):
    """One zeta (zeta_h = zeta_v) per state, fitted on that state's $a_i^2$ divided by those of the
    reference state (Appendix B's reference point), as the zeta-against-Zm analysis needs:
    {state: zeta, or None where it is not determined: the contrast does not depend on zeta, or the
    fit stops at a bound of its range: bound zetas (clump2's 1e-20 to 1e-19) ranked against Zm
    would be a correlation of round-off}."""
    A_n, A_s = parts
    ref = (tab["E"][reference], A_n[reference], A_s[reference])
    out = {}
    for k, sid in enumerate(tab["state"]):
        if k == reference:
            continue
        try:
            fit = _zeta.fit_common(tab["E"][[k]], A_n[[k]], A_s[[k]], min_states=1, reference=ref)
        except ValueError:
            fit = None
        out[sid] = None if fit is None or fit["at_bound"] else fit["zeta"]
    return out


def zeta_trend(tab, zetas, band=0.02, low_fraction=0.2):
    """How the per-state zeta (zeta_per_state) follows Zm: Spearman's rank correlation over the
    states with a zeta, and the mean zeta of the states within `band` of the highest Zm and of those
    in the lowest `low_fraction` of the Zm range (with their counts). The paper's zeta is one
    number for all states: rho near 0 and the two means equal."""
    zm = tab["Zm"]
    ok = [(zm[tab["state"].index(s)], v) for s, v in zetas.items() if v is not None]
    rho = None
    if len(ok) >= 3:
        from scipy.stats import spearmanr
        rho = float(spearmanr([a for a, _ in ok], [b for _, b in ok]).statistic)
    hi = [v for z, v in ok if z >= zm.max() - band]
    lo = [v for z, v in ok if z < zm.min() + low_fraction * (zm.max() - zm.min())]
    mean = lambda v: float(np.mean(v)) if v else None  # noqa: E731
    return dict(rho=rho, high=mean(hi), n_high=len(hi), low=mean(lo), n_low=len(lo),
                n_undetermined=sum(v is None for v in zetas.values()), n=len(zetas))


def nu_floor(tab):
    r"""The $\nu_{ij}$ RMSE that no zeta can beat: Eq. (22) fed with each state's own DEM $a_i^2$ (Eq. 25)
    and nu0 (hyperelastic.scalar_moduli), against the DEM $\nu_{ij}$. Any prediction through Eq. (22)
    has $\nu_{ij} a_j^2/a_i^2$ equal in all six pairs, which the DEM values are not; this is how far
    they are from it. Returns dict(rmse, mean_abs (the mean of $\lvert\nu_{ij}\rvert$), relative (rmse / mean_abs))."""
    off = ~np.eye(3, dtype=bool)
    err, vals = [], []
    for E, nu in zip(tab["E"], tab["nu"]):
        m = hyperelastic.scalar_moduli(E, nu)
        pred = m["nu0"] * m["a2"][:, None] / m["a2"][None, :]
        err.append((pred - nu)[off])
        vals.append(nu[off])
    err, vals = np.concatenate(err), np.concatenate(vals)
    rmse, mean_abs = float(np.sqrt(np.mean(err ** 2))), float(np.mean(np.abs(vals)))
    return dict(rmse=rmse, mean_abs=mean_abs, relative=rmse / mean_abs)


def relative_nu_rmse(tab, rmse):
    r"""An RMSE of $\nu_{ij}$ relative to the values: rmse over the mean of $\lvert\nu_{ij}\rvert$ over the states' six $\nu_{ij}$."""
    off = ~np.eye(3, dtype=bool)
    return float(rmse / np.mean(np.abs(tab["nu"][:, off])))


def a2_regression(a2_dem, a2_mic):
    """Micromechanical against DEM $a_i^2$ over all states and axes: least-squares slope and
    intercept of mic = slope dem + intercept, and Pearson's r. Appendix B expects a line; with
    the right zeta its slope is 1."""
    x, y = np.ravel(a2_dem), np.ravel(a2_mic)
    slope, intercept = np.polyfit(x, y, 1)
    return dict(slope=float(slope), intercept=float(intercept), r=float(np.corrcoef(x, y)[0, 1]))


UNBOUNDED_ZETA = (-1.0, 5.0)  # the per-state search when the bounded fit stops at 0 (zeta_below_zero)


def zeta_below_zero(tab, parts, reference, bounds=UNBOUNDED_ZETA):
    """One zeta per state, as zeta_per_state, but searched below 0 as well: C = A_n + zeta A_s
    (Eq. 37, one zeta, linear in it) is defined for negative zeta as long as $E_i$ stay positive.
    A negative optimum says that no reduction of the tangential stiffness reaches the DEM contrast:
    the model's contrast is too small even with the tangential springs removed.
    Returns {state: zeta} (None where the misfit has no interior minimum in `bounds`)."""
    from scipy import optimize
    A_n, A_s = parts

    def a2(k, z):
        return _zeta.a_squared(_young_one(A_n[k], A_s[k], z))

    dem = tab["a2_dem"] / tab["a2_dem"][reference]
    out = {}
    for k, sid in enumerate(tab["state"]):
        if k == reference:
            continue

        def misfit(z, k=k):
            with np.errstate(invalid="ignore"):
                r = a2(k, z) / a2(reference, z) - dem[k]
            return float(np.sum(r ** 2)) if np.all(np.isfinite(r)) else 1e3

        fit = optimize.minimize_scalar(misfit, bounds=bounds, method="bounded", options=dict(xatol=1e-8))
        inside = bounds[0] + 1e-4 < fit.x < bounds[1] - 1e-4
        out[sid] = float(fit.x) if inside else None
    return out


def _young_one(A_n, A_s, z):
    """E_i of Eq. (40) from C = A_n + z A_s (one zeta, any sign)."""
    voigt = np.zeros((6, 6))
    voigt[:3, :3] = _zeta._normal(A_n) + z * _zeta._normal(A_s)
    from trueaniso import engines
    return np.asarray(engines.orthotropic_moduli(voigt)["E"], dtype=float)


def table2_slopes(tab, fits, paper, zm_ref):
    """dK/dZm and dG/dZm (MPa per unit of Zm) at the reference Zm: of the paper's quadratic and of
    ours (2 c1 Zm + c2), with a straight line over our states as a check of our quadratic's slope
    (over a narrow Zm range the quadratic's coefficients are ill-conditioned, its slope less so);
    ratio = paper / ours (quadratic)."""
    out = {}
    for name in ("K", "G"):
        pc, c = paper[name], fits[name][:3]
        p_slope = 2 * pc[0] * zm_ref + pc[1]
        o_slope = 2 * c[0] * zm_ref + c[1]
        line = float(np.polyfit(tab["Zm"], tab[name] / 1e6, 1)[0])
        out[name] = dict(paper=float(p_slope), ours=float(o_slope), ours_line=line,
                         ratio=float(p_slope / o_slope) if o_slope else None)
    return out
