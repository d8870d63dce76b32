r"""Micro-structure of the contact network and its micromechanical elastic prediction.

The numbers come from the C++ engines (measure/Fabric, theory/Micromechanics); this module names
them for the study's tables:

- ``fabric(scene)``: Zm (Eq. 14), R (15), H (16), B (33), M (34, 3x3x3x3), Nc/V by Eq. (36)
  and by count, void ratio, mean normal force, Nc, Np, Np0, Np1;
- ``prediction(scene, zeta, density)``: $C_{ijkl}$ (Eq. 37), its orthotropic Voigt matrix
  (Appendix A) and $E_i$, $\nu_{ij}$, $G_{ij}$ (Eqs. 39-42);
- ``fabric_row(scene, zeta)``: one flat dict of CSV columns;
- ``recorder(every)`` / ``history(recorder)``: the engine that records every N steps;
- ``fabric_from_interactions(O)``: the same measures in plain Python over YADE's
  ``O.interactions`` (no trueaniso scene needed); slow, kept as the peer and the benchmark.

The scene's contacts must come from a force evaluation at its current configuration (a step of
the engine chain); a freshly loaded or imported scene needs one first.
"""
import math

import numpy as np

from . import engines

__all__ = ["fabric", "prediction", "recorder", "history", "NoContacts"]

AXES = "xyz"
DENSITIES = ("eq36", "count")
# The M components that enter Appendix A (A1-A9).
M_COLUMNS = ((0, 0, 0, 0), (1, 1, 1, 1), (2, 2, 2, 2),
             (0, 0, 1, 1), (1, 1, 0, 0), (0, 0, 2, 2), (2, 2, 0, 0), (1, 1, 2, 2), (2, 2, 1, 1),
             (1, 2, 1, 2), (2, 1, 2, 1), (0, 2, 0, 2), (2, 0, 2, 0), (0, 1, 0, 1), (1, 0, 1, 0))
_SYM = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_SHEAR = ("yz", "xz", "xy")


def _check_density(density):
    if density not in DENSITIES:
        raise ValueError("density must be one of %s (Nc/V by Eq. 36 or counted), got %r" % (DENSITIES, density))
    return density


class NoContacts(ValueError):
    """Zm, R, H, B, M are averages over contacts: a scene without any has none of them."""


def _require_contacts(scene, nc):
    if nc == 0:
        raise NoContacts("the scene has no contact carrying a normal force, so Zm, R, H, B and M are undefined "
                         "(a loose or unloaded packing, or a loaded scene before its first force evaluation)")


def fabric(scene):
    """The fabric measures of the scene's last force evaluation (paper sections 3.2 and 4.2).

    Returns:
        dict: ``Zm`` (Eq. 14), ``R`` (Eq. 15) and ``H`` (Eq. 16) as 3x3 arrays, ``B`` (Eq. 33, 3x3),
        ``M`` (Eq. 34, 3x3x3x3), ``NcV_eq36`` and ``NcV_count`` (contacts per volume by Eq. 36 and
        counted, docs/fabric.md), ``e`` (void ratio), ``mean_N`` (mean normal force), ``Nc``,
        ``Np``, ``Np0``, ``Np1``, ``mean_r3`` and ``volume``.

    Raises:
        NoContacts: a scene without a contact carrying a normal force (never a quiet NaN).

    Example:
        >>> from trueaniso import specimen_file, fabric
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> f = fabric.fabric(scene)
        >>> print("Zm = %.2f, R_zz = %.3f" % (f["Zm"], f["R"][2, 2]))
        Zm = 5.84, R_zz = 0.335
    """
    f = engines.fabric(scene)
    _require_contacts(scene, int(f["Nc"]))
    return f


def prediction(scene, zeta=1.0, density="eq36"):
    r"""The micromechanical elastic prediction of the scene's contact network (Eqs. 33-42).

    Args:
        scene: the engines' Scene, its forces evaluated at its state.
        zeta: the rotation factor of Eq. (37) (the paper fits 0.552 for spheres; 1: kinematic).
        density: $N_c/V$ by "eq36" (the paper's Eq. 36, read with the mean $r^3$) or "count".

    Returns:
        dict: ``C`` ($C_{ijkl}$, Eq. 37, 3x3x3x3), ``voigt`` (its orthotropic 6x6, Appendix A), ``E``
        ($E_x$, $E_y$, $E_z$), ``nu`` (3x3, nu[i, j] = $\nu_{ij}$), ``G`` ($G_{yz}$, $G_{xz}$, $G_{xy}$), in Pa, with
        ``zeta`` and ``contact_density``.

    Raises:
        NoContacts: a scene without a loaded contact.
        ValueError: an unknown `density`, a zeta outside [0, 5].

    Example:
        >>> from trueaniso import specimen_file, fabric
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> p = fabric.prediction(scene, zeta=0.552)
        >>> print("E_z = %.0f MPa, nu_zx = %.3f" % (p["E"][2] / 1e6, p["nu"][2, 0]))
        E_z = 346 MPa, nu_zx = 0.102
    """
    _require_contacts(scene, int(engines.coordination(scene)["Nc"]))
    return engines.micromechanical_prediction(scene, float(zeta), _check_density(density))


def prediction_from(f, shear_modulus, poisson, zeta=1.0, density="eq36"):
    """The same prediction from a fabric dict (or a history row) and the particle material."""
    m = _material(shear_modulus, poisson)
    ncv = f["NcV_eq36"] if _check_density(density) == "eq36" else f["NcV_count"]
    return engines.micromechanics(np.asarray(f["B"]), np.asarray(f["M"]), float(ncv), m.Cn, m.Cs,
                                  float(zeta))


def _material(shear_modulus, poisson):
    s = engines.Scene()
    s.shear_modulus = shear_modulus
    s.poisson = poisson
    return s


def fabric_row(scene, zeta=1.0, density="eq36"):
    r"""Flat dict of CSV columns: counts, ``R_``, ``H_``, ``B_`` (6 independent components each), the M
    components of Appendix A, NcV_eq36, NcV_count, e, mean_N, and the micromechanical moduli
    mic_E_i, mic_nu_ij, mic_G_ij for the given zeta (prefixed so they cannot be mistaken for
    the probe's measured $E_i$, $\nu_{ij}$)."""
    f = fabric(scene)  # refuses a scene without contacts
    p = engines.micromechanics(f["B"], f["M"], float(f["NcV_eq36"] if _check_density(density) == "eq36"
                                                     else f["NcV_count"]),
                               scene.Cn, scene.Cs, float(zeta))
    out = row(f, p, zeta, density)
    out.update(gap_columns(scene))
    return out


def gap_column(tolerance):
    """'Zm_gap1e-3' for 1e-3: the column of Zm counted with that gap tolerance."""
    mantissa, exponent = ("%.6e" % tolerance).split("e")
    return "Zm_gap%se%d" % (mantissa.rstrip("0").rstrip("."), int(exponent))


def gap_columns(scene, tolerance=None):
    """Zm and $N_c$ with near-contacts counted: pairs whose gap is below tolerance (default
    engines.GAP_TOLERANCE) times their mean diameter (measure/Coordination.hpp)."""
    tol = engines.GAP_TOLERANCE if tolerance is None else tolerance
    z = engines.coordination_gap(scene, tol)
    name = gap_column(tol)
    return {name: float(z["Zm"]), "Nc" + name[2:]: int(z["Nc"])}


def row(f, p, zeta, density):
    """The columns of fabric_row from a fabric dict and a prediction dict."""
    out = dict(Zm=float(f["Zm"]), Nc=int(f["Nc"]), Np=int(f["Np"]), Np0=int(f["Np0"]), Np1=int(f["Np1"]))
    for name in ("R", "H", "B"):
        t = np.asarray(f[name])
        for i, j in _SYM:
            out["%s_%s%s" % (name, AXES[i], AXES[j])] = float(t[i, j])
    M = np.asarray(f["M"])
    for idx in M_COLUMNS:
        out["M_" + "".join(AXES[k] for k in idx)] = float(M[idx])
    out.update(NcV_eq36=float(f["NcV_eq36"]), NcV_count=float(f["NcV_count"]), e=float(f["e"]),
               mean_N=float(f["mean_N"]), mic_zeta=float(zeta), mic_density=density)
    for i in range(3):
        out["mic_E_" + AXES[i]] = float(p["E"][i])
    for i in range(3):
        for j in range(3):
            if i != j:
                out["mic_nu_" + AXES[i] + AXES[j]] = float(p["nu"][i, j])
    for k, name in enumerate(_SHEAR):
        out["mic_G_" + name] = float(p["G"][k])
    return out


def recorder(every=100):
    """A FabricRecorder engine, which records the fabric every `every` steps of a simulation.

    Add it to a chain after the contact forces (``dem.Chain(scene, controllers=[rec])``); `history`
    reads what it recorded.

    Raises:
        ValueError: `every` < 1.

    Example:
        >>> from trueaniso import specimen_file, fabric, dem
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> rec = fabric.recorder(every=10)
        >>> dem.Chain(scene, controllers=[rec]).run(30)
        30
        >>> len(fabric.history(rec)["Zm"])
        3
    """
    every = int(every)
    if every < 1:
        raise ValueError("every must be >= 1 step")
    r = engines.FabricRecorder()
    r.every = every
    return r


def history(rec):
    """Every record of a FabricRecorder (`recorder`).

    Returns:
        dict: numpy arrays with one entry per record: ``step``, ``time``, the measures of `fabric`
        (tensors as (n, 3, 3) and (n, 3, 3, 3, 3) arrays).

    Example:
        >>> from trueaniso import specimen_file, fabric, dem
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> rec = fabric.recorder(every=10)
        >>> dem.Chain(scene, controllers=[rec]).run(20)
        20
        >>> h = fabric.history(rec)
        >>> list(h["step"]), h["R"].shape
        ([108000, 108010], (2, 3, 3))
    """
    return rec.history()


def history_rows(rec, shear_modulus, poisson, zeta=1.0, density="eq36"):
    """One fabric_row-like dict per record, with step and time."""
    h = history(rec)
    rows = []
    for k in range(len(h["step"])):
        f = {key: v[k] for key, v in h.items()}
        r = row(f, prediction_from(f, shear_modulus, poisson, zeta, density), zeta, density)
        r.update(step=int(h["step"][k]), time=float(h["time"][k]))
        rows.append(r)
    return rows


def fabric_from_interactions(O, material=None):
    """Zm, R, H, B, M, Nc/V (Eq. 36 and count), e and mean_N in plain Python over YADE's
    O.interactions, for a periodic scene of spheres: branch L = pos2 + hSize cellDist - pos1,
    n = geom.normal, N = norm(phys.normalForce), rbar from the two radii (Eq. 7); e from the sphere
    volumes. The definitions are those of fabric(scene); only the code differs."""
    from yade import Sphere  # noqa: F401 - fails clearly outside yade-double
    h = np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)])
    radius, pos = {}, {}
    for b in O.bodies:
        if b is None:
            continue
        radius[b.id] = b.shape.radius
        pos[b.id] = np.array([b.state.pos[0], b.state.pos[1], b.state.pos[2]])
    count = dict.fromkeys(radius, 0)
    n_list, L_list, w_list, N_list = [], [], [], []
    for I in O.interactions:
        if not I.isReal:
            continue
        N = I.phys.normalForce.norm()
        if not N > 0:
            continue
        i, j = I.id1, I.id2
        nrm = I.geom.normal
        cd = I.cellDist
        L = pos[j] + h @ np.array([cd[0], cd[1], cd[2]], dtype=float) - pos[i]
        r1, r2 = radius[i], radius[j]
        rbar = 2.0 * r1 * r2 / (r1 + r2)
        n_list.append((nrm[0], nrm[1], nrm[2]))
        L_list.append(L)
        w_list.append((rbar * N) ** (1.0 / 3.0))
        N_list.append(N)
        count[i] += 1
        count[j] += 1
    n = np.array(n_list)
    L = np.array(L_list)
    w = np.array(w_list)
    nc = len(w)
    per = np.array(list(count.values()))
    np0, np1 = int(np.sum(per == 0)), int(np.sum(per == 1))
    zm = (2.0 * nc - np1) / (len(per) - np0 - np1)
    V = abs(np.linalg.det(h))
    r = np.array(list(radius.values()))
    vs = 4.0 / 3.0 * math.pi * np.sum(r ** 3)
    e = (V - vs) / vs
    return dict(Zm=zm, Nc=nc, Np=len(per), Np0=np0, Np1=np1,
                R=np.einsum("ci,cj->ij", n, n) / nc,
                H=np.einsum("ci,cj->ij", L, L) / nc,
                B=np.einsum("c,ci,cj->ij", w, L, L) / nc,
                M=np.einsum("c,ci,cj,ck,cl->ijkl", w, L, n, L, n, optimize=True) / nc,
                NcV_eq36=3.0 * zm / (8.0 * math.pi * (1.0 + e) * np.mean(r ** 3)),
                NcV_count=nc / V, e=e, mean_N=float(np.mean(N_list)), volume=V)
